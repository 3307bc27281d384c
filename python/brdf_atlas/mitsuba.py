"""A Mitsuba 3 BSDF plugin, ``"brdf_atlas"``: the material at a latent
point of a brdf-atlas model, or a MERL file, in any Mitsuba scene.

>>> import mitsuba as mi
>>> mi.set_variant("llvm_ad_rgb")
>>> import brdf_atlas.mitsuba
>>> brdf_atlas.mitsuba.register()
>>> bsdf = mi.load_dict({"type": "brdf_atlas", "model": "atlas.atlas",
...                      "x": 0.3, "y": -0.5})             # doctest: +SKIP

Properties:

- ``model`` (string): a model file, with ``x`` and ``y`` (floats) for a
  2-D model, or ``latent`` (a string of ``latent_dim`` numbers separated by
  commas or blanks) for any;
- or ``filename`` (string): a MERL ``.binary`` file, evaluated directly
  (the same nearest-bin lookup);
- ``blend`` (string, optional, with ``model``): ``"floor"`` (default: the
  GP's values lifted softly onto a floor at 0.3 times a convex blend's:
  never negative, no pass over the store; the material the map shows),
  ``"gp"`` (the GP's own blend, clamped to >= 0) or ``"plausible"`` (the
  stepped rule's, which keeps the material non-negative and its albedo at
  most 1; one pass over the model's store when the scene loads, none per
  ray);
- ``sampling`` (string, optional): ``"tabulated"`` (default: a table of
  the material's own lobe mixed with 10% cosine sampling) or ``"cosine"``.

The BSDF is one-sided glossy reflection: zero when either direction is at
or below the surface. In the vectorised variants (``llvm_ad_rgb``, ...)
each method makes one call into brdf_atlas for the whole wavefront, with
the GIL released; that needs Dr.Jit's evaluated mode, so :func:`register`
turns symbolic loops and calls off. In ``scalar_rgb`` each call is one ray.
Models are opened once per path and shared.
"""

import threading

import numpy as np

from ._native import Material, Model
from .errors import InputError

__all__ = ["register", "open_model"]

_models = {}
_models_lock = threading.Lock()
_classes = {}


def open_model(path):
    """The :class:`brdf_atlas.Model` at ``path``, opened once and shared."""
    key = str(path)
    with _models_lock:
        model = _models.get(key)
        if model is None:
            model = _models[key] = Model(key)
        return model


def _has(props, key):
    try:
        return key in props
    except TypeError:  # Mitsuba before 3.6
        return props.has_property(key)


def _material(props):
    """The :class:`brdf_atlas.Material` a plugin's properties describe."""

    def has(key):
        return _has(props, key)

    if has("filename"):
        if has("model"):
            raise InputError("brdf_atlas BSDF: give either 'model' or 'filename', not both")
        if has("blend"):
            raise InputError("brdf_atlas BSDF: 'blend' applies to a 'model', not to a 'filename'")
        return Material.from_merl(str(props["filename"])), str(props["filename"])
    if not has("model"):
        raise InputError(
            "brdf_atlas BSDF: expected a 'model' property (a model file) or a 'filename' (a MERL file)"
        )
    path = str(props["model"])
    model = open_model(path)
    if has("latent"):
        text = str(props["latent"]).replace(",", " ").split()
        try:
            x = [float(v) for v in text]
        except ValueError:
            raise InputError(
                f"brdf_atlas BSDF: latent = {props['latent']!r}: expected {model.latent_dim} numbers"
            ) from None
    elif has("x") or has("y"):
        x = [float(props.get("x", 0.0)), float(props.get("y", 0.0))]
    else:
        raise InputError(
            f"brdf_atlas BSDF: {path}: expected the latent point as 'x' and 'y', or 'latent'"
        )
    blend = str(props.get("blend", "floor")) if has("blend") else "floor"
    label = f"{path} at {x}" if blend == "floor" else f"{path} at {x} ({blend} blend)"
    return model.material(x, blend=blend), label


def _bsdf_class(mi, dr):
    """The plugin's class for the current variant (a subclass of ``mi.BSDF``)."""
    scalar = mi.variant().startswith("scalar")

    def rows(v):
        """A Dr.Jit 3-vector (or 2-vector) as an (n, k) numpy view."""
        a = np.asarray(v) if scalar else v.numpy()
        a = a.reshape(1, -1) if a.ndim == 1 else a.T
        if not np.isfinite(a).all():
            # Lanes that are not active may hold anything; they are masked out.
            a = np.nan_to_num(a, nan=0.0, posinf=0.0, neginf=0.0)
        return a

    def color(a):
        if scalar:
            return mi.Color3f(float(a[0, 0]), float(a[0, 1]), float(a[0, 2]))
        return mi.Color3f(np.ascontiguousarray(a.T, dtype=np.float32))

    def vector(a):
        if scalar:
            return mi.Vector3f(float(a[0, 0]), float(a[0, 1]), float(a[0, 2]))
        return mi.Vector3f(np.ascontiguousarray(a.T, dtype=np.float32))

    def floats(a):
        if scalar:
            return mi.Float(float(a[0]))
        return mi.Float(np.ascontiguousarray(a, dtype=np.float32))

    glossy = mi.BSDFFlags.GlossyReflection

    class AtlasBSDF(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.material, self.label = _material(props)
            self.sampling = str(props.get("sampling", "tabulated"))
            if self.sampling not in ("tabulated", "cosine"):
                raise InputError(
                    f"brdf_atlas BSDF: sampling = {self.sampling!r}: expected 'tabulated' or 'cosine'"
                )
            flags = glossy | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _enabled(self, ctx):
            return ctx.is_enabled(glossy, 0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = rows(si.wi)
            u = rows(sample2)
            wo, pdf, value = self.material.sample(wi, u, self.sampling)
            cos_o = np.clip(wo[:, 2], 0.0, None)
            with np.errstate(divide="ignore", invalid="ignore"):
                weight = np.where(pdf[:, None] > 0.0, value * (cos_o / pdf)[:, None], 0.0)
            bs = dr.zeros(mi.BSDFSample3f, 1 if scalar else dr.width(si.wi))
            bs.wo = vector(wo)
            bs.pdf = floats(pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+glossy)
            bs.sampled_component = mi.UInt32(0)
            ok = active & (bs.pdf > 0.0) & self._enabled(ctx)
            return bs, dr.select(ok, color(weight), 0.0)

        def eval(self, ctx, si, wo, active=True):
            wo_ = rows(wo)
            value = self.material.eval(rows(si.wi), wo_)
            value *= np.clip(wo_[:, 2], 0.0, None)[:, None]
            return dr.select(active & self._enabled(ctx), color(value), 0.0)

        def pdf(self, ctx, si, wo, active=True):
            p = self.material.pdf(rows(si.wi), rows(wo), self.sampling)
            return dr.select(active & self._enabled(ctx), floats(p), 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            wo_ = rows(wo)
            value, p = self.material.eval_pdf(rows(si.wi), wo_, self.sampling)
            value *= np.clip(wo_[:, 2], 0.0, None)[:, None]
            on = active & self._enabled(ctx)
            return dr.select(on, color(value), 0.0), dr.select(on, floats(p), 0.0)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"AtlasBSDF[{self.label}, sampling={self.sampling}]"

    return AtlasBSDF


def register():
    """Register the ``"brdf_atlas"`` BSDF with Mitsuba for the current
    variant (call ``mitsuba.set_variant`` first; call again after changing
    it). In a vectorised variant this turns Dr.Jit's symbolic loops and
    calls off, so that each method sees a whole evaluated wavefront."""
    import drjit as dr
    import mitsuba as mi

    variant = mi.variant()
    if variant is None:
        raise RuntimeError("brdf_atlas.mitsuba.register: set a Mitsuba variant first (mitsuba.set_variant)")
    if not variant.startswith("scalar"):
        dr.set_flag(dr.JitFlag.SymbolicLoops, False)
        dr.set_flag(dr.JitFlag.SymbolicCalls, False)
    cls = _classes.get(variant)
    if cls is None:
        cls = _classes[variant] = _bsdf_class(mi, dr)
    mi.register_bsdf("brdf_atlas", lambda props: cls(props))
