"""Bad input raises brdf_atlas.errors classes with the command-line tool's
one-line message, and nothing is left half done."""

import pathlib
import subprocess

import numpy as np
import pytest

import brdf_atlas as ba
from conftest import NOISE


def cli_error(cli, *args):
    """The one-line message the command-line tool prints for a failure."""
    r = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 1, r
    line = r.stderr.strip()
    assert line.startswith("error: ") and "\n" not in line
    return line[len("error: "):]


def test_a_missing_model(cli, tmp_path):
    path = tmp_path / "missing.atlas"
    with pytest.raises(ba.FileError) as e:
        ba.Model(path)
    assert isinstance(e.value, OSError) and isinstance(e.value, ba.Error)
    assert str(e.value) == cli_error(cli, "eval", path, "--at", "0,0", "--wi", "0,0", "--wo", "0,0")


def test_a_file_that_is_not_a_model(cli, tmp_path):
    path = tmp_path / "text.atlas"
    path.write_text("hello\n")
    with pytest.raises(ba.FormatError) as e:
        ba.Model(path)
    assert isinstance(e.value, ValueError)
    assert str(e.value) == cli_error(cli, "reconstruct", path, "--at", "0,0", "-o", tmp_path / "o.binary")
    assert str(path) in str(e.value)


def test_bad_merl_files(cli, tmp_path, log_model):
    short = tmp_path / "short.binary"
    short.write_bytes(b"\x5a\x00\x00\x00" * 3 + b"\x00" * 16)
    with pytest.raises(ba.FormatError) as e:
        ba.read_merl(short)
    assert str(e.value) == cli_error(cli, "info", short)
    assert str(e.value).startswith(f"{short}: header says 90x90x90")
    with pytest.raises(ba.FormatError) as e:
        log_model.locate(short)
    assert str(e.value) == cli_error(cli, "locate", log_model.path, short)
    with pytest.raises(ba.FileError):
        ba.read_merl(tmp_path / "absent.binary")


def test_latent_points(log_model, cli):
    wi = np.array([[0.0, 0.0, 1.0]])
    with pytest.raises(ba.InputError) as e:
        log_model.eval([0.1, 0.2, 0.3], wi, wi)
    assert "expected 2 finite coordinates" in str(e.value)
    assert isinstance(e.value, ValueError)
    with pytest.raises(ba.InputError, match="finite coordinates"):
        log_model.table([np.nan, 0.0])
    with pytest.raises(ba.InputError, match="latent point: expected a sequence of numbers, got a str"):
        log_model.weights("0.1, 0.2")


def test_direction_arrays(log_model):
    x = [0.0, 0.0]
    good = np.zeros((4, 3))
    good[:, 2] = 1
    with pytest.raises(ba.InputError, match=r"wi: expected an array of shape \(n, 3\), got shape \[4, 2\]"):
        log_model.eval(x, good[:, :2], good)
    with pytest.raises(ba.InputError, match=r"wo: expected an array of shape \(n, 3\)"):
        log_model.eval(x, good, good.ravel())
    with pytest.raises(ba.InputError, match="wi and wo: expected arrays of the same shape"):
        log_model.eval(x, good, good[:3])
    bad = good.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ba.InputError, match=r"wo\[2\] = \[0, NaN, 1\]: expected finite direction vectors"):
        log_model.eval(x, good, bad)
    with pytest.raises(ba.InputError, match=r"wi\[2\]"):
        log_model.material(x).pdf(bad.astype(np.float32), good)
    with pytest.raises(ba.InputError, match=r"u: expected shape \(4, 2\)"):
        log_model.material(x).sample(good, np.zeros((3, 2)))
    with pytest.raises(ba.InputError, match="method \"importance\": expected"):
        log_model.material(x).pdf(good, good, "importance")
    # Lists are read as float64; at or below the horizon gives zero.
    assert log_model.eval(x, [[0, 0, 1]], [[0, 0, -1]]).tolist() == [[0.0, 0.0, 0.0]]


def test_tables(tmp_path):
    with pytest.raises(ba.InputError, match=r"expected shape \(3, n_theta_h, n_theta_d, n_phi_d\), got \[2, 3, 4, 5\]"):
        ba.write_merl(tmp_path / "t.binary", np.zeros((2, 3, 4, 5)))
    t = np.zeros((3, 2, 2, 4))
    t[2, 1, 0, 3] = -0.5
    with pytest.raises(ba.InputError, match=r"table\[2, 1, 0, 3\] = -0.5: expected reflectance >= 0"):
        ba.write_merl(tmp_path / "t.binary", t)
    assert not (tmp_path / "t.binary").exists()
    with pytest.raises(ba.InputError):
        ba.write_merl(tmp_path / "t.binary", np.zeros((3, 0, 2, 2)))


def test_fit_options_and_data(data, cli, tmp_path):
    out = tmp_path / "m.atlas"
    with pytest.raises(ba.InputError) as e:
        ba.fit(data, out, noise=-1.0)
    assert str(e.value) == cli_error(cli, "fit", data, "-o", out, "--noise", "-1")
    with pytest.raises(ba.InputError) as e:
        ba.fit(data, out, q=5)
    assert "q = 5 needs more materials than latent dimensions" in str(e.value)
    with pytest.raises(ba.InputError, match="transform \"cubic\": expected"):
        ba.fit(data, out, transform="cubic")
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(ba.FormatError) as e:
        ba.fit(empty, out)
    assert str(e.value) == cli_error(cli, "fit", empty, "-o", out)
    assert not out.exists() and not (tmp_path / "m.atlas.store").exists()


def test_a_failing_progress_callback_is_raised_after_the_fit(data, tmp_path):
    seen = []

    def progress(label, done, total):
        seen.append((label, done, total))
        if label == "optimise":
            raise KeyError("stop")

    with pytest.raises(KeyError):
        ba.fit(data, tmp_path / "m.atlas", progress=progress)
    labels = [s[0] for s in seen]
    assert labels[0] != "optimise" and "optimise" in labels
    assert all(0 <= d <= t for _, d, t in seen if t)


def test_fit_saves_the_map_fields_unless_asked_not_to(data, tmp_path):
    # As `brdf-atlas fit`: the map fields of the default view and of
    # [-3, 3]^2 saved beside the model (its name with .fields).
    out = tmp_path / "m.atlas"
    r = ba.fit(data, out, noise=NOISE)
    fields = tmp_path / "m.fields"
    assert pathlib.Path(r["fields"]) == fields
    assert fields.stat().st_size > 0
    assert r["seconds"]["map_field"] > 0
    bare = tmp_path / "bare" / "m.atlas"
    bare.parent.mkdir()
    r = ba.fit(data, bare, noise=NOISE, map_field=False)
    assert r["fields"] is None
    assert not (bare.parent / "m.fields").exists()
