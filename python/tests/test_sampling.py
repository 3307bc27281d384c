"""The importance sampler: a density that integrates to 1, samples that
follow it, estimates that agree with cosine sampling's, and less variance
than cosine sampling on a glossy lobe."""

import numpy as np
import pytest

import brdf_atlas as ba
from conftest import COPPER, LAMBERTIAN, point_of


def hemisphere_grid(n_theta=256, n_phi=512):
    """Midpoint directions and solid angles of the cells of a (theta, phi)
    grid of the hemisphere, uniform in both."""
    edges = np.arange(n_theta + 1) * (np.pi / 2 / n_theta)
    t = 0.5 * (edges[1:] + edges[:-1])
    p = (np.arange(n_phi) + 0.5) * (2 * np.pi / n_phi)
    T, P = np.meshgrid(t, p, indexing="ij")
    d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
    band = np.cos(edges[:-1]) - np.cos(edges[1:])
    dw = np.broadcast_to((band * (2 * np.pi / n_phi))[:, None], T.shape).ravel()
    return d, dw


def incident(theta_deg, phi_deg=30.0):
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


@pytest.mark.parametrize("method", ["tabulated", "cosine"])
def test_the_density_integrates_to_one(log_model, method):
    material = log_model.material(point_of(log_model, COPPER))
    d, dw = hemisphere_grid()
    for theta in (0.0, 35.0, 70.0, 88.0):
        wi = np.broadcast_to(incident(theta), d.shape)
        p = material.pdf(wi, d, method)
        assert abs(np.sum(p * dw) - 1.0) < 5e-3, (theta, np.sum(p * dw))
        assert material.pdf(wi[:1], -d[:1], method)[0] == 0.0


def test_samples_carry_their_density_and_follow_it(log_model):
    material = log_model.material(point_of(log_model, COPPER))
    n = 200_000
    rng = np.random.default_rng(11)
    wi = np.broadcast_to(incident(40.0), (n, 3))
    wo, pdf, value = material.sample(wi, rng.uniform(size=(n, 2)))
    assert np.allclose(np.linalg.norm(wo, axis=1), 1.0) and (wo[:, 2] >= 0).all() and (pdf > 0).all()
    assert np.array_equal(pdf, material.pdf(wi, wo))
    assert np.array_equal(value, material.eval(wi, wo))
    # The share of samples in each of 32 elevation bands against the
    # density's integral over the band (bands whole cells of the grid).
    d, dw = hemisphere_grid()
    p = material.pdf(np.broadcast_to(incident(40.0), d.shape), d)
    theta = np.arccos(np.clip(d[:, 2], -1, 1))
    edges = np.arange(33) * (np.pi / 64)
    band = np.digitize(theta, edges) - 1
    expected = np.bincount(band, weights=p * dw, minlength=32)
    observed = np.histogram(np.arccos(np.clip(wo[:, 2], -1, 1)), edges)[0] / n
    sigma = np.sqrt(expected * (1 - expected) / n)
    assert np.all(np.abs(observed - expected) < 5 * sigma + 1e-3), (observed, expected)


def estimates(material, theta, method, n, seed):
    """Per-sample estimates of the directional albedo at incidence theta."""
    rng = np.random.default_rng(seed)
    wi = np.broadcast_to(incident(theta), (n, 3))
    wo, pdf, value = material.sample(wi, rng.uniform(size=(n, 2)), method)
    return value.mean(axis=1) * wo[:, 2] / pdf


def test_tabulated_sampling_is_unbiased_and_beats_cosine_on_a_metal(log_model):
    material = log_model.material(point_of(log_model, COPPER))
    n = 200_000
    for theta in (10.0, 45.0, 75.0):
        tab = estimates(material, theta, "tabulated", n, 1)
        cos = estimates(material, theta, "cosine", n, 2)
        se = np.sqrt(tab.var() / n + cos.var() / n)
        assert abs(tab.mean() - cos.mean()) < 4 * se, (theta, tab.mean(), cos.mean(), se)
        assert cos.var() > 3 * tab.var(), (theta, cos.var() / tab.var())


def test_a_lambertian_material_is_sampled_like_cosine(raw_model):
    # The GP's blend reproduces the material at its own latent point.
    material = raw_model.material(point_of(raw_model, "lambert-a"), blend="gp")
    tab = estimates(material, 30.0, "tabulated", 100_000, 3)
    # f cos / p is constant for cosine sampling of a Lambertian: the table
    # must be close to it (its cells are piecewise constant).
    assert abs(tab.mean() - np.mean(LAMBERTIAN["lambert-a"])) < 2e-3
    assert tab.std() < 0.05 * tab.mean()


def test_a_merl_file_and_its_latent_point_sample_alike(log_model, data):
    from_file = ba.Material.from_merl(data / f"{COPPER}.binary")
    from_model = log_model.material(point_of(log_model, COPPER), blend="gp")
    d, dw = hemisphere_grid(64, 128)
    wi = np.broadcast_to(incident(30.0), d.shape)
    assert np.allclose(from_file.pdf(wi, d), from_model.pdf(wi, d), rtol=1e-3, atol=1e-6)
