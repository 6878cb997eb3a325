"""A small importance-sampled renderer: spheres of Facet materials under a
sky, NumPy only (the directions come from facet's samplers), into a PNG.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/render_sphere.py [out.png] [--size 200] [--spp 64]

Each pixel of an orthographic camera that hits a unit sphere gets a shading
frame (n, t, b); wo is the camera direction in that frame; kernel.sample
draws wi with its weight f cos / pdf, and the pixel is the mean of
weight x L(wi) over --spp samples, where L is a procedural sky: a blue
gradient over a grey ground and a warm sun (a disc ten degrees across, so
that sampling the BSDF alone converges). Tone mapping: exposure, a filmic
curve, sRGB.
"""

import argparse
import os

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import facet  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
MATERIALS = os.path.join(HERE, "..", "..", "materials")
SPHERES = ["plastic", "gold", "car_paint", "brushed_metal"]
SUN = np.array([0.55, 0.55, 0.63]) / np.linalg.norm([0.55, 0.55, 0.63])
SUN_COS = np.cos(np.radians(5.0))


def sky(d):
    """Radiance arriving from world directions d (..., 3)."""
    up = d[..., 1]
    t = np.clip(up, 0, 1)[..., None]
    horizon, zenith = np.array([0.9, 0.95, 1.0]), np.array([0.25, 0.45, 0.95])
    above = (1 - t) * horizon + t * zenith
    ground = np.array([0.18, 0.16, 0.14]) * np.clip(0.5 - up, 0.2, 1)[..., None]
    L = np.where(up[..., None] > 0, above, ground)
    sun = (d @ SUN) > SUN_COS
    return L + sun[..., None] * np.array([60.0, 52.0, 40.0])


def render(kernel, size, spp, rng):
    """(size, size, 3) linear radiance of one sphere."""
    ys, xs = np.mgrid[0:size, 0:size]
    x = (xs + 0.5) / size * 2.2 - 1.1
    y = 1.1 - (ys + 0.5) / size * 2.2
    hit = x * x + y * y < 1
    n = np.stack([x[hit], y[hit], np.sqrt(1 - x[hit] ** 2 - y[hit] ** 2)], axis=1)
    # A frame per hit point: t along the sphere's "longitude" (brushed metal
    # shows its grain along it), b = n x t.
    t = np.cross([0.0, 1.0, 0.0], n)
    t /= np.maximum(np.linalg.norm(t, axis=1, keepdims=True), 1e-9)
    b = np.cross(n, t)
    view = np.array([0.0, 0.0, 1.0])
    wo = np.stack([t @ view, b @ view, n @ view], axis=1)
    wo[:, 2] = np.maximum(wo[:, 2], 1e-4)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    m = len(wo)
    color = np.zeros((m, 3))
    wo_rows = np.ascontiguousarray(wo.T, dtype=np.float32)
    for _ in range(spp):
        u = rng.random((3, m), dtype=np.float32)
        wi, pdf, weight = kernel.sample(wo_rows, u)
        world = wi[0][:, None] * t + wi[1][:, None] * b + wi[2][:, None] * n
        color += weight.T * sky(world)
    image = np.zeros((size, size, 3))
    image[~hit] = sky(np.array([0.0, 0.0, 1.0])) * 0.35
    image[hit] = color / spp
    return image


def tonemap(x):
    x = x * 0.6
    mapped = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)  # a filmic curve (ACES fit)
    mapped = np.clip(mapped, 0, 1)
    return np.where(mapped <= 0.0031308, 12.92 * mapped, 1.055 * mapped ** (1 / 2.4) - 0.055)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", nargs="?", default="spheres.png")
    parser.add_argument("--size", type=int, default=200)
    parser.add_argument("--spp", type=int, default=64)
    args = parser.parse_args()
    rng = np.random.default_rng(3)
    images = []
    for name in SPHERES:
        kernel = facet.compile(os.path.join(MATERIALS, name + ".mat"))
        images.append(render(kernel, args.size, args.spp, rng))
    plt.imsave(args.out, tonemap(np.concatenate(images, axis=1)))
    print(f"wrote {args.out}: {', '.join(SPHERES)}, {args.size} px, {args.spp} samples per pixel")


if __name__ == "__main__":
    main()
