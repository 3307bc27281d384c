"""Render a sphere in the material of a few points of a brdf-atlas map, and
write the renders side by side as one PNG.

    python contact_sheet.py MODEL OUT.png [--points X,Y X,Y ...] [--size 256] [--spp 64]

The sphere is lit by an environment built with numpy: a dim blue sky
gradient, a warm ground and one small bright light, so that diffuse
colour, highlights and their sharpness all show. Without --points, four
points spread over the map: the latent points of the materials farthest
apart, and the midpoint of the first two. Mitsuba's LLVM variant renders
(scalar_rgb when it is missing, much slower).
"""

import argparse
import sys
import time

import numpy as np

import brdf_atlas


def environment(width=256, height=128):
    """An equirectangular environment (height x width x 3, linear RGB)."""
    theta = (np.arange(height) + 0.5) / height * np.pi  # 0 at the zenith
    phi = (np.arange(width) + 0.5) / width * 2 * np.pi
    T, P = np.meshgrid(theta, phi, indexing="ij")
    up = np.cos(T)
    sky = np.stack([0.25 + 0.2 * up, 0.35 + 0.25 * up, 0.6 + 0.3 * up], axis=-1) * (up > 0)[..., None]
    ground = np.array([0.12, 0.09, 0.06]) * (up <= 0)[..., None]
    # A small bright light 40 degrees above the horizon.
    d = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1)
    sun = np.array([np.cos(np.radians(40)) * np.cos(0.6), np.cos(np.radians(40)) * np.sin(0.6), np.sin(np.radians(40))])
    light = (d @ sun > np.cos(np.radians(4)))[..., None] * np.array([60.0, 55.0, 48.0])
    return (sky + ground + light).astype(np.float32)


def default_points(model):
    """The two materials farthest apart, their midpoint, and the material
    farthest from both."""
    latent = model.latent
    d = np.linalg.norm(latent[:, None, :] - latent[None, :, :], axis=-1)
    i, j = np.unravel_index(np.argmax(d), d.shape)
    k = int(np.argmax(np.minimum(d[i], d[j])))
    return [latent[i], 0.5 * (latent[i] + latent[j]), latent[j], latent[k]]


def render(mi, model_path, x, size, spp, env):
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 3},
        "sensor": {
            "type": "perspective",
            "fov": 30,
            "to_world": T().look_at(origin=[0, -4.2, 1.2], target=[0, 0, 0], up=[0, 0, 1]),
            "film": {"type": "hdrfilm", "width": size, "height": size, "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "environment": {"type": "envmap", "bitmap": mi.Bitmap(env),
                        "to_world": T().rotate([1, 0, 0], 90)},
        "sphere": {"type": "sphere", "bsdf": {"type": "brdf_atlas", "model": str(model_path),
                                               "latent": " ".join(repr(float(v)) for v in x)}},
    })
    return np.array(mi.render(scene))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("model")
    parser.add_argument("out")
    parser.add_argument("--points", nargs="*", default=None, help="latent points X,Y")
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--spp", type=int, default=64)
    args = parser.parse_args()

    import mitsuba as mi
    try:
        mi.set_variant("llvm_ad_rgb")
    except Exception as e:  # no usable libLLVM
        print(f"llvm_ad_rgb unavailable ({e}); using scalar_rgb", file=sys.stderr)
        mi.set_variant("scalar_rgb")
    import brdf_atlas.mitsuba
    brdf_atlas.mitsuba.register()

    model = brdf_atlas.Model(args.model)
    points = ([np.array([float(v) for v in p.split(",")]) for p in args.points]
              if args.points else default_points(model))
    env = environment()
    tiles = []
    for x in points:
        start = time.perf_counter()
        tiles.append(render(mi, args.model, x, args.size, args.spp, env))
        print(f"({', '.join(f'{v:.3f}' for v in x)}): {time.perf_counter() - start:.1f} s")
    gap = np.ones((args.size, 4, 3), dtype=np.float32)
    sheet = np.concatenate(sum(([t, gap] for t in tiles), [])[:-1], axis=1)
    bitmap = mi.Bitmap(sheet).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
    bitmap.write(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
