"""The Mitsuba 3 plugin: white furnaces of Lambertian latent points, and a
rough metal's latent point against its own MERL file, in the scalar and
the vectorised (LLVM) variants."""

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba", reason="the Mitsuba tests need mitsuba (pip install mitsuba)")

import brdf_atlas.mitsuba as bam  # noqa: E402
from conftest import COPPER, LAMBERTIAN, point_of  # noqa: E402

VARIANTS = ["scalar_rgb", "llvm_ad_rgb"]


def use(variant):
    mi.set_variant(variant)
    bam.register()


def render(bsdf, *, spp, res=16, seed=0, view=(0.0, 0.0, 1.0)):
    """A plane under a constant environment of radiance 1, seen by an
    orthographic camera along `view`: every pixel sees the plane's
    directional albedo for that view direction. Returns the per-channel
    mean over pixels and its standard error."""
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "direct"},
        "sensor": {
            "type": "orthographic",
            # Far enough that the whole film lies above the plane.
            "to_world": T().look_at(origin=list(3 * np.asarray(view)), target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp, "seed": seed},
        },
        "emitter": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "plane": {"type": "rectangle", "to_world": T().scale([4, 4, 1]), "bsdf": bsdf},
    })
    pixels = np.array(mi.render(scene)).reshape(-1, 3)
    return pixels.mean(axis=0), pixels.std(axis=0, ddof=1) / np.sqrt(len(pixels))


def at(model, name):
    """The BSDF of the GP's blend at material `name`'s latent point: the GP
    reproduces the material there (to its noise), which the renders below
    are checked against; the default rule, the soft floor, lifts low values
    by a share of a convex blend of the neighbours."""
    x, y = point_of(model, name)
    return {"type": "brdf_atlas", "model": str(model.path), "x": float(x), "y": float(y),
            "blend": "gp"}


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("which", ["raw_model", "log_model"])
def test_white_furnace_of_a_lambertian_latent_point(request, variant, which):
    model = request.getfixturevalue(which)
    use(variant)
    spp, res = (64, 24) if variant.startswith("scalar") else (256, 16)
    rho = np.array(LAMBERTIAN["lambert-a"])
    mean, se = render(at(model, "lambert-a"), spp=spp, res=res)
    assert np.all(se < 0.002 * rho), se
    assert np.all(np.abs(mean - rho) < 0.01 * rho), (mean, rho)


@pytest.mark.parametrize("variant", VARIANTS)
def test_a_rough_metal_renders_as_its_merl_file(log_model, data, variant):
    use(variant)
    spp = 32 if variant.startswith("scalar") else 256
    view = (0.0, -0.8, 0.6)
    latent, se_a = render(at(log_model, COPPER), spp=spp, seed=1, view=view)
    merl, se_b = render({"type": "brdf_atlas", "filename": str(data / f"{COPPER}.binary")},
                        spp=spp, seed=2, view=view)
    se = np.sqrt(se_a**2 + se_b**2)
    assert np.all(se < 0.01 * merl), se
    assert np.all(np.abs(latent - merl) < 4 * se + 1e-3 * merl), (latent, merl, se)
    # And the directional albedo agrees with a quadrature of the file's own values.
    import brdf_atlas as ba
    material = ba.Material.from_merl(data / f"{COPPER}.binary")
    wi = np.array(view) / np.linalg.norm(view)
    n_t, n_p = 512, 1024
    edges = np.arange(n_t + 1) * (np.pi / 2 / n_t)
    t = 0.5 * (edges[1:] + edges[:-1])
    p = (np.arange(n_p) + 0.5) * (2 * np.pi / n_p)
    T, P = np.meshgrid(t, p, indexing="ij")
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    dw = np.broadcast_to(((np.cos(edges[:-1]) - np.cos(edges[1:])) * 2 * np.pi / n_p)[:, None], T.shape).ravel()
    f = material.eval(np.broadcast_to(wi, wo.shape), wo)
    albedo = np.sum(f * (wo[:, 2] * dw)[:, None], axis=0)
    assert np.all(np.abs(merl - albedo) < 4 * se_b + 5e-3 * albedo), (merl, albedo)


def test_bad_plugin_properties(log_model):
    use("scalar_rgb")
    with pytest.raises(Exception, match="expected a 'model' property"):
        mi.load_dict({"type": "brdf_atlas"})
    with pytest.raises(Exception, match="missing.atlas: No such file or directory"):
        mi.load_dict({"type": "brdf_atlas", "model": "missing.atlas", "x": 0.0, "y": 0.0})
    with pytest.raises(Exception, match="expected 2 finite coordinates"):
        mi.load_dict({"type": "brdf_atlas", "model": str(log_model.path), "latent": "0.1 0.2 0.3"})
    with pytest.raises(Exception, match="sampling = 'mis'"):
        mi.load_dict({"type": "brdf_atlas", "model": str(log_model.path), "x": 0.0, "y": 0.0,
                      "sampling": "mis"})


@pytest.mark.parametrize("variant", VARIANTS)
def test_a_plausible_point_renders_as_the_file_reconstruct_writes(log_model, cli, tmp_path, variant):
    import subprocess
    x = [0.9, -0.95]
    # The rule moves this point's weights (else this compares GP materials).
    assert not np.array_equal(log_model.table(x, blend="plausible"), log_model.table(x, blend="gp"))
    out = tmp_path / "plausible.binary"
    subprocess.run([str(cli), "reconstruct", str(log_model.path), "--at", f"{x[0]!r},{x[1]!r}",
                    "--blend", "plausible", "-o", str(out)], check=True, capture_output=True)
    use(variant)
    spp = 16 if variant.startswith("scalar") else 64
    view = (0.0, -0.8, 0.6)
    bsdf = {"type": "brdf_atlas", "model": str(log_model.path), "x": x[0], "y": x[1]}
    plausible, _ = render(dict(bsdf, blend="plausible"), spp=spp, seed=3, view=view)
    from_file, _ = render({"type": "brdf_atlas", "filename": str(out)}, spp=spp, seed=3, view=view)
    # The same samples of the same values (the file rounds them to MERL's doubles).
    assert np.allclose(plausible, from_file, rtol=1e-6, atol=0), (plausible, from_file)
    # Without a rule, the default one: the soft floor, as `reconstruct` writes by default.
    out = tmp_path / "default.binary"
    subprocess.run([str(cli), "reconstruct", str(log_model.path), "--at", f"{x[0]!r},{x[1]!r}",
                    "-o", str(out)], check=True, capture_output=True)
    default, _ = render(bsdf, spp=spp, seed=3, view=view)
    floor, _ = render(dict(bsdf, blend="floor"), spp=spp, seed=3, view=view)
    from_file, _ = render({"type": "brdf_atlas", "filename": str(out)}, spp=spp, seed=3, view=view)
    assert np.array_equal(default, floor)
    assert np.allclose(default, from_file, rtol=1e-6, atol=0), (default, from_file)
    with pytest.raises(Exception, match='blend rule "convex"'):
        mi.load_dict(dict(bsdf, blend="convex"))
