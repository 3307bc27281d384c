"""Measure what docs/performance.md reports for the Python package: BSDF
evaluations per second (the package, the C library, through Mitsuba's BSDF
interface), white-furnace errors, and the variance of the tabulated
importance sampler against cosine sampling.

    python measure.py --cli target/release/brdf-atlas --clib target/release/libbrdf_atlas_c.so WORKDIR

It writes into WORKDIR: 8 synthetic materials at 90 x 90 x 180 and their
log model (the speed figures), and the test suite's small set (a rough
copper, a rough plastic and three Lambertian materials at 30 x 30 x 60)
with its raw and log models (the furnace and variance figures).
"""

import argparse
import ctypes
import pathlib
import subprocess
import time

import numpy as np

import brdf_atlas as ba

LAMBERTIAN = {"lambert-a": (0.2, 0.5, 0.8), "lambert-b": (0.7, 0.3, 0.1), "lambert-c": (0.5, 0.5, 0.5)}


def median_time(f, runs=5):
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def hemisphere(n, rng):
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def speed(args, work):
    full = work / "full"
    if not (full / "atlas.atlas").exists():
        subprocess.run([args.cli, "synth", "--count", "8", str(full / "merl")], check=True, capture_output=True)
        ba.fit(full / "merl", full / "atlas.atlas")
    model = ba.Model(full / "atlas.atlas")
    x = model.latent[0]
    n = 1_000_000
    rng = np.random.default_rng(1)
    wi, wo = hemisphere(n, rng), hemisphere(n, rng)
    material = model.material(x)
    material.eval(wi, wo)
    print(f"model: {model}, point {x.tolist()}, {n} direction pairs")
    print(f"  Model.eval (weights solved each call):  {median_time(lambda: model.eval(x, wi, wo)):.3f} s")
    print(f"  Material.eval (bins remembered):        {median_time(lambda: material.eval(wi, wo)):.3f} s")
    lib = ctypes.CDLL(args.clib)
    lib.brdf_atlas_model_open.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_void_p)]
    lib.brdf_atlas_model_eval_batch.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                                ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t,
                                                ctypes.c_void_p, ctypes.c_size_t]
    handle = ctypes.c_void_p()
    assert lib.brdf_atlas_model_open(str(model.path).encode(), ctypes.byref(handle)) == 0
    out = np.empty_like(wi)
    c_call = lambda: lib.brdf_atlas_model_eval_batch(handle, x[0], x[1], wi.ctypes.data, wo.ctypes.data,  # noqa: E731
                                                      n, out.ctypes.data, out.size)
    print(f"  C ABI brdf_atlas_model_eval_batch:      {median_time(c_call):.3f} s")

    import drjit as dr
    import mitsuba as mi
    import brdf_atlas.mitsuba

    mi.set_variant("llvm_ad_rgb")
    brdf_atlas.mitsuba.register()
    bsdf = mi.load_dict({"type": "brdf_atlas", "model": str(model.path), "x": float(x[0]), "y": float(x[1])})
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))
    wo_m = mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32))
    sample2 = mi.Point2f(rng.uniform(size=(2, n)).astype(np.float32))
    sample1 = mi.Float(rng.uniform(size=n).astype(np.float32))
    ctx = mi.BSDFContext()
    dr.eval(si, wo_m, sample1, sample2)
    bsdf.eval_pdf(ctx, si, wo_m)  # the tabulated sampler is built on first use
    for name, call in [("eval", lambda: dr.eval(bsdf.eval(ctx, si, wo_m))),
                       ("pdf", lambda: dr.eval(bsdf.pdf(ctx, si, wo_m))),
                       ("eval_pdf", lambda: dr.eval(bsdf.eval_pdf(ctx, si, wo_m))),
                       ("sample", lambda: dr.eval(bsdf.sample(ctx, si, sample1, sample2)))]:
        print(f"  Mitsuba llvm_ad_rgb BSDF.{name + ':':10s}        {median_time(call):.3f} s")
    mi.set_variant("scalar_rgb")
    brdf_atlas.mitsuba.register()
    bsdf = mi.load_dict({"type": "brdf_atlas", "model": str(model.path), "x": float(x[0]), "y": float(x[1])})
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(*wi[0])
    w = mi.Vector3f(*wo[0])
    calls = 20_000
    t = median_time(lambda: [bsdf.eval(ctx, si, w) for _ in range(calls)], runs=3)
    print(f"  Mitsuba scalar_rgb BSDF.eval:           {t / calls * 1e6:.1f} us a call")


def small_set(args, work):
    d = work / "small"
    if not (d / "merl").exists():
        subprocess.run([args.cli, "synth", "--count", "2", "--dims", "30,30,60", str(d / "merl")],
                       check=True, capture_output=True)
        for name, rho in LAMBERTIAN.items():
            t = np.empty((3, 30, 30, 60))
            t[:] = (np.array(rho) / np.pi)[:, None, None, None]
            ba.write_merl(d / "merl" / f"{name}.binary", t)
    models = {}
    for transform in ("raw", "log"):
        out = d / f"{transform}.atlas"
        if not out.exists():
            ba.fit(d / "merl", out, transform=transform, noise=1e-9)
        models[transform] = ba.Model(out)
    return d, models


def furnace(mi, bsdf, spp, res, view=(0, 0, 1), integrator=None, seed=0):
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "integrator": integrator or {"type": "direct"},
        "sensor": {"type": "orthographic",
                   "to_world": T().look_at(origin=list(3 * np.asarray(view, float)), target=[0, 0, 0], up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"},
                            "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp, "seed": seed}},
        "emitter": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
        "plane": {"type": "rectangle", "to_world": T().scale([4, 4, 1]), "bsdf": bsdf},
    })
    return np.array(mi.render(scene)).reshape(-1, 3)


def quality(args, work):
    import mitsuba as mi
    import brdf_atlas.mitsuba

    d, models = small_set(args, work)
    rho = np.array(LAMBERTIAN["lambert-a"])
    print("white furnace, plane at lambert-a's latent point, rho = (0.2, 0.5, 0.8), direct integrator:")
    for variant, spp, res in [("scalar_rgb", 256, 32), ("llvm_ad_rgb", 1024, 64)]:
        mi.set_variant(variant)
        brdf_atlas.mitsuba.register()
        for transform, model in models.items():
            x = model.latent[model.names.index("lambert-a")]
            # The GP's blend: it reproduces lambert-a at its latent point.
            bsdf = {"type": "brdf_atlas", "model": str(model.path), "x": float(x[0]), "y": float(x[1]),
                    "blend": "gp"}
            px = furnace(mi, bsdf, spp, res)
            mean, se = px.mean(0), px.std(0, ddof=1) / np.sqrt(len(px))
            err = (mean - rho) / rho
            print(f"  {variant:12s} {transform}: {mean.round(5).tolist()}, relative error "
                  f"{(100 * err).round(3).tolist()} %, standard error {(100 * se / rho).round(3).tolist()} % "
                  f"({res}x{res} pixels, {spp} spp)")

    copper = "000-metal-copper-r0.18"
    model = models["log"]
    material = model.material(model.latent[model.names.index(copper)])
    n = 1_000_000
    rng = np.random.default_rng(4)
    print(f"variance of the directional-albedo estimate f cos / p, {copper} at its latent point (log model), "
          f"{n} samples, channel mean:")
    for theta in (0, 30, 60, 80):
        t = np.radians(theta)
        wi = np.broadcast_to([np.sin(t), 0.0, np.cos(t)], (n, 3))
        est = {}
        for method in ("cosine", "tabulated"):
            wo, pdf, value = material.sample(wi, rng.uniform(size=(n, 2)), method)
            est[method] = value.mean(axis=1) * wo[:, 2] / pdf
        print(f"  theta_i {theta:2d}: mean {est['tabulated'].mean():.4f} (cosine {est['cosine'].mean():.4f}), "
              f"variance cosine / tabulated = {est['cosine'].var() / est['tabulated'].var():.1f}")
    mi.set_variant("llvm_ad_rgb")
    brdf_atlas.mitsuba.register()
    x = model.latent[model.names.index(copper)]
    bsdf_only = {"type": "direct", "emitter_samples": 0, "bsdf_samples": 1}
    var = {}
    for method in ("cosine", "tabulated"):
        px = furnace(mi, {"type": "brdf_atlas", "model": str(model.path), "x": float(x[0]), "y": float(x[1]),
                          "sampling": method}, 1, 256, view=(0, -0.8, 0.6), integrator=bsdf_only)
        var[method] = px.mean(axis=1).var()
    print(f"  in Mitsuba (plane seen at 53 degrees, constant environment, BSDF samples only, 1 spp): "
          f"pixel variance cosine / tabulated = {var['cosine'] / var['tabulated']:.1f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cli", required=True)
    parser.add_argument("--clib", required=True)
    parser.add_argument("workdir", type=pathlib.Path)
    args = parser.parse_args()
    args.workdir.mkdir(parents=True, exist_ok=True)
    speed(args, args.workdir)
    quality(args, args.workdir)


if __name__ == "__main__":
    main()
