"""Point queries against independent references: the C library (bit for
bit), the command-line tool's eval (at the precision it prints) and
reconstruct (the file's bytes), and the tables themselves."""

import ctypes
import json
import subprocess

import numpy as np
import pytest

import brdf_atlas as ba
from conftest import DIMS, LAMBERTIAN, NOISE, point_of


def angle_pairs(n, seed):
    """n pairs of (theta_i, phi_i, theta_o, phi_o) in degrees, some below the horizon."""
    rng = np.random.default_rng(seed)
    a = np.column_stack([rng.uniform(0, 95, n), rng.uniform(-180, 360, n),
                         rng.uniform(0, 95, n), rng.uniform(-180, 360, n)])
    return np.round(a, 3)


def direction(theta, phi):
    t, p = np.radians(theta), np.radians(phi)
    return np.column_stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


def c_eval(clib, model_path, x, wi, wo):
    lib = ctypes.CDLL(str(clib))
    lib.brdf_atlas_model_open.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_void_p)]
    lib.brdf_atlas_model_eval_batch.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double,
                                                ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t,
                                                ctypes.c_void_p, ctypes.c_size_t]
    lib.brdf_atlas_model_free.argtypes = [ctypes.c_void_p]
    handle = ctypes.c_void_p()
    assert lib.brdf_atlas_model_open(str(model_path).encode(), ctypes.byref(handle)) == 0
    wi, wo = np.ascontiguousarray(wi), np.ascontiguousarray(wo)
    out = np.empty_like(wi)
    status = lib.brdf_atlas_model_eval_batch(handle, x[0], x[1], wi.ctypes.data, wo.ctypes.data,
                                             len(wi), out.ctypes.data, out.size)
    lib.brdf_atlas_model_free(handle)
    assert status == 0
    return out


@pytest.mark.parametrize("which", ["log_model", "raw_model"])
def test_eval_equals_the_c_library_and_the_cli(request, which, cli, clib, tmp_path):
    model = request.getfixturevalue(which)
    x = [0.1234567, -0.3]
    angles = angle_pairs(400, 7)
    wi, wo = direction(angles[:, 0], angles[:, 1]), direction(angles[:, 2], angles[:, 3])
    ours = model.eval(x, wi, wo)
    # The C library: NaN where a pair has no value, where the binding gives 0.
    theirs = c_eval(clib, model.path, x, wi, wo)
    none = np.isnan(theirs)
    assert none.any() and (~none).any()
    assert np.array_equal(np.where(none, 0.0, theirs), ours)
    assert np.all(ours[none.any(axis=1)] == 0.0)
    # The command-line tool prints 10 significant digits: compare at exactly those.
    batch = tmp_path / "pairs.txt"
    batch.write_text("".join(" ".join(repr(float(v)) for v in row) + "\n" for row in angles))
    out = subprocess.run([str(cli), "eval", str(model.path), "--at", f"{x[0]!r},{x[1]!r}",
                          "--batch", str(batch)], check=True, capture_output=True, text=True).stdout
    # Two header lines, a row a pair, then the confidence line.
    rows = out.splitlines()[2:]
    assert rows[-1].startswith("confidence:")
    rows = rows[:-1]
    assert len(rows) == len(angles)
    for row, value in zip(rows, ours):
        fields = row.split()
        if "below" in row:
            assert np.all(value == 0.0), row
        else:
            printed = [float(f) for f in fields[4:7]]
            assert printed == [float(f"{v:.9e}") for v in value], row
    # float32 directions: the same as float64 ones of the same values.
    assert np.array_equal(model.eval(x, wi.astype(np.float32), wo.astype(np.float32)),
                          model.eval(x, wi.astype(np.float32).astype(np.float64),
                                     wo.astype(np.float32).astype(np.float64)))
    # Strided views are read in place, with the same answers.
    both = np.concatenate([wi, wo], axis=1)
    assert np.array_equal(model.eval(x, both[:, :3], both[:, 3:]), ours)


def test_table_equals_the_file_reconstruct_writes(log_model, cli, tmp_path):
    x = [0.25, -0.125]
    out = tmp_path / "new.binary"
    subprocess.run([str(cli), "reconstruct", str(log_model.path), "--at", "0.25,-0.125", "-o", str(out)],
                   check=True, capture_output=True)
    raw = log_model.table(x, raw=True)
    assert raw.shape == (3,) + DIMS
    data = out.read_bytes()
    assert np.frombuffer(data[:12], "<i4").tolist() == list(DIMS)
    assert np.array_equal(np.frombuffer(data[12:], "<f8").reshape(raw.shape), raw)
    physical = log_model.table(x)
    assert np.array_equal(physical, ba.read_merl(out), equal_nan=True)
    assert np.array_equal(ba.read_merl(out, raw=True), raw)
    # MERL's channel scales, and NaN exactly where the file says -1.
    scale = np.array([1.0, 1.15, 1.66]) / 1500.0
    measured = raw >= 0
    assert np.array_equal(np.isnan(physical), ~measured)
    assert np.allclose(physical[measured], (raw * scale[:, None, None, None])[measured], rtol=1e-15)


def test_material_and_model_agree(log_model):
    x = [-0.2, 0.4]
    rng = np.random.default_rng(3)
    wi, wo = rng.normal(size=(1000, 3)), rng.normal(size=(1000, 3))
    material = log_model.material(x)
    assert np.array_equal(material.eval(wi, wo), log_model.eval(x, wi, wo))
    assert np.array_equal(material.table(), log_model.table(x), equal_nan=True)
    # A second pass reads the remembered bins: the same bits.
    assert np.array_equal(material.eval(wi, wo), log_model.eval(x, wi, wo))


def test_model_properties_and_weights(log_model, data):
    names = sorted(p.stem for p in data.glob("*.binary"))
    assert log_model.names == names
    assert len(log_model) == 5 and log_model.latent_dim == 2
    assert log_model.latent.shape == (5, 2) and log_model.latent.dtype == np.float64
    assert log_model.transform == "log" and log_model.dims == DIMS
    w = log_model.weights(point_of(log_model, "lambert-a"))
    assert w.shape == (5,)
    assert abs(w[names.index("lambert-a")] - 1.0) < 1e-3


def test_a_written_table_reads_back(tmp_path):
    t = np.random.default_rng(1).uniform(0, 2, size=(3, 4, 5, 6))
    t[:, 2, 3, 4] = np.nan
    ba.write_merl(tmp_path / "t.binary", t)
    back = ba.read_merl(tmp_path / "t.binary")
    assert np.allclose(back, t, rtol=1e-15, equal_nan=True)
    assert np.isnan(back[:, 2, 3, 4]).all()


@pytest.mark.parametrize("which", ["log_model", "raw_model"])
def test_locate_finds_a_material_where_it_was_fitted(request, which, data):
    model = request.getfixturevalue(which)
    for name in LAMBERTIAN:
        found = model.locate(data / f"{name}.binary")
        assert found.nearest[0][0] == name
        assert found.rmse < 0.01 * found.spread
        table = ba.read_merl(data / f"{name}.binary")
        again = model.locate(table)
        assert again.point == found.point and again.rmse == found.rmse


@pytest.mark.parametrize("which", ["log_model", "raw_model"])
def test_albedo_map(request, which):
    model = request.getfixturevalue(which)
    m = model.albedo_map(24, 16)
    assert m.shape == (16, 24, 3) and m.dtype == np.float32 and np.isfinite(m).all()
    # A one-pixel map of the GP's blend centred on a Lambertian material's
    # latent point: its albedo (exact for raw; a log map integrates, with a
    # sampled rule). The default, the soft floor, lifts it by up to 0.6%.
    samples, rtol = (None, 2e-3) if model.transform == "raw" else (4096, 5e-3)
    for name, rho in LAMBERTIAN.items():
        x, y = point_of(model, name)
        view = (x - 0.01, x + 0.01, y - 0.01, y + 0.01)
        one = model.albedo_map(1, 1, view=view, samples=samples, blend="gp")
        assert np.allclose(one[0, 0], rho, rtol=rtol), (name, one[0, 0])


def test_the_default_map_is_drawn_from_the_fields_fit_saved(data, tmp_path):
    # As every other program's: the map of a model fresh from `fit` is
    # drawn from the fields saved beside it (shown by doubling every saved
    # albedo value and finding the map doubled), not integrated per pixel.
    out = tmp_path / "m.atlas"
    ba.fit(data, out, noise=NOISE)
    before = ba.Model(out).albedo_map(40, 30)
    per_pixel = ba.Model(out).albedo_map(40, 30, samples=256)
    fields = tmp_path / "m.fields"
    doc = json.loads(fields.read_text())
    doubled = 0
    for entry in doc["entries"]:
        for patch in (entry.get("field") or {}).get("albedo", []):
            patch["values"] = [2.0 * v for v in patch["values"]]
            doubled += 1
    assert doubled > 0
    fields.write_text(json.dumps(doc))
    after = ba.Model(out).albedo_map(40, 30)
    assert before.max() > 0.01
    assert np.allclose(after, 2.0 * before, rtol=1e-6, atol=1e-9)
    # A sample count asks for per-pixel integration: the file plays no part.
    assert np.array_equal(ba.Model(out).albedo_map(40, 30, samples=256), per_pixel)


@pytest.mark.parametrize("which", ["log_model", "raw_model"])
def test_the_default_map_is_the_floor_rule_s(request, which):
    model = request.getfixturevalue(which)
    gp = model.albedo_map(24, 16, blend="gp")
    floor = model.albedo_map(24, 16)
    assert np.array_equal(floor, model.albedo_map(24, 16, blend="floor"))
    assert floor.shape == gp.shape and np.isfinite(floor).all() and (floor >= 0).all()
    # The floor lifts every value a little (and those the GP drives below
    # its floor a lot): not the GP's map.
    assert not np.array_equal(floor, gp)
    # The plausible rule's steps need a pass over the store per point: no map.
    with pytest.raises(ba.Error, match="no map"):
        model.albedo_map(4, 4, blend="plausible")


@pytest.mark.parametrize("blend", ["gp", "plausible", "floor"])
def test_plausibility_and_confidence_equal_the_cli_record(log_model, cli, tmp_path, blend):
    x = [0.9, -0.95]
    out = subprocess.run([str(cli), "reconstruct", str(log_model.path), "--at", f"{x[0]!r},{x[1]!r}",
                          "--blend", blend, "--json", "-o", str(tmp_path / "m.binary")],
                         check=True, capture_output=True, text=True).stdout
    rec = json.loads(out)
    p = log_model.plausibility(x, blend=blend)
    for key in ["clamped_reflectance", "clamped_values", "max_albedo", "max_albedo_incidence"]:
        assert p[key] == rec["plausibility"][key], key
    assert p["plausible"] == rec["plausible"]
    if blend == "floor":
        # The soft floor never lets a value below zero.
        assert p["clamped_reflectance"] == 0.0 and p["clamped_values"] == 0.0
    c = log_model.confidence(x)
    assert c["variance"] == rec["confidence"]["variance"]
    # Far from every material the model knows nothing, and says so.
    far = log_model.confidence([30.0, 30.0])
    assert far["low"] and far["variance"] > 0.999 and abs(far["weight_sum"]) < 1e-6
    with pytest.raises(ba.Error, match="blend rule"):
        log_model.plausibility(x, blend="convex")


def test_plausible_queries_agree_with_each_other_and_the_cli(log_model, cli, tmp_path):
    x = [0.9, -0.95]
    angles = angle_pairs(300, 11)
    wi, wo = direction(angles[:, 0], angles[:, 1]), direction(angles[:, 2], angles[:, 3])
    material = log_model.material(x, blend="plausible")
    assert "plausible" in repr(material)
    assert np.array_equal(log_model.eval(x, wi, wo, blend="plausible"), material.eval(wi, wo))
    # The file reconstruct writes holds the same values.
    out = tmp_path / "plausible.binary"
    subprocess.run([str(cli), "reconstruct", str(log_model.path), "--at", f"{x[0]!r},{x[1]!r}",
                    "--blend", "plausible", "-o", str(out)], check=True, capture_output=True)
    raw = log_model.table(x, raw=True, blend="plausible")
    assert np.array_equal(raw, ba.Material.from_merl(out).table(raw=True))
    assert not np.array_equal(raw, log_model.table(x, raw=True))
    with pytest.raises(ba.Error, match="blend rule"):
        log_model.material(x, blend="convex")
