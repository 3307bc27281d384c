"""Shared fixtures: the command-line tool and the C library of this
checkout, and a small data set with its models.

The data set: two synthetic materials written by ``brdf-atlas synth``
(a rough copper, GGX alpha 0.18, and a rough yellow plastic) and three
Lambertian materials written with ``write_merl``, at 30 x 30 x 60. The
models are fitted with noise 1e-9, small enough that the reconstruction at
a material's own latent point is that material to about 1e-4.
"""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import brdf_atlas as ba

REPO = pathlib.Path(__file__).resolve().parents[2]
DIMS = (30, 30, 60)
LAMBERTIAN = {"lambert-a": (0.2, 0.5, 0.8), "lambert-b": (0.7, 0.3, 0.1), "lambert-c": (0.5, 0.5, 0.5)}
COPPER = "000-metal-copper-r0.18"
NOISE = 1e-9


def _built(env, default, what):
    path = pathlib.Path(os.environ.get(env, REPO / "target" / "release" / default))
    if not path.exists():
        pytest.fail(f"{path}: missing; build {what} first (cargo build --release -p brdf-atlas -p brdf-atlas-ffi) or set {env}")
    return path


@pytest.fixture(scope="session")
def cli():
    """The brdf-atlas binary (BRDF_ATLAS_BIN, else target/release/brdf-atlas)."""
    return _built("BRDF_ATLAS_BIN", "brdf-atlas", "the command-line tool")


@pytest.fixture(scope="session")
def clib():
    """The C library (BRDF_ATLAS_C_LIB, else target/release/libbrdf_atlas_c.so)."""
    return _built("BRDF_ATLAS_C_LIB", "libbrdf_atlas_c.so", "the C library")


def lambertian_table(rho):
    t = np.empty((3,) + DIMS)
    t[:] = (np.asarray(rho, dtype=float) / np.pi)[:, None, None, None]
    return t


@pytest.fixture(scope="session")
def data(tmp_path_factory, cli):
    d = tmp_path_factory.mktemp("merl")
    subprocess.run([str(cli), "synth", "--count", "2", "--dims", ",".join(map(str, DIMS)), str(d)],
                   check=True, capture_output=True)
    for name, rho in LAMBERTIAN.items():
        ba.write_merl(d / f"{name}.binary", lambertian_table(rho))
    assert (d / f"{COPPER}.binary").exists()
    return d


def _fit(data, tmp_path_factory, transform):
    out = tmp_path_factory.mktemp(f"model-{transform}") / f"{transform}.atlas"
    ba.fit(data, out, transform=transform, noise=NOISE)
    return ba.Model(out)


@pytest.fixture(scope="session")
def log_model(data, tmp_path_factory):
    return _fit(data, tmp_path_factory, "log")


@pytest.fixture(scope="session")
def raw_model(data, tmp_path_factory):
    return _fit(data, tmp_path_factory, "raw")


def point_of(model, name):
    return model.latent[model.names.index(name)]
