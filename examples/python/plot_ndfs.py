"""Plots the distribution of normals D and the directional albedo E of
several NDFs at one roughness, into a PNG.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/plot_ndfs.py [out.png] [--samples N]

D(theta_h) comes from eval itself: with no masking and no Fresnel,
f = D / (4 cos_i cos_o), and at wi = wo the half vector is wi, so
D(theta) = 4 f cos^2(theta). E(mu) is the mean sampling weight
f cos_i / pdf of the kernel's own sampler (Smith height-correlated masking,
F = 1): the energy a single-scattering lobe keeps, which falls at grazing
angles and for rougher lobes (what Kulla-Conty puts back).
"""

import argparse

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import facet  # noqa: E402

NDFS = [
    ("ggx", "ggx(alpha)"),
    ("beckmann", "beckmann(alpha)"),
    ("gtr (gamma 1.5)", "gtr(alpha, 1.5)"),
    ("student_t (gamma 3)", "student_t(alpha, 3)"),
    ("epd (p 0.6)", "epd(alpha, 0.6)"),
    ("gaussian", "gaussian(alpha)"),
]


def kernel(ndf, masking, **options):
    text = (f"material m {{ input alpha = 0.3 in 0.001 .. 1; ndf = {ndf}; masking = {masking}; "
            f"fresnel = none; }}")
    return facet.compile(text=text, **options)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", nargs="?", default="ndfs.png")
    parser.add_argument("--samples", type=int, default=200_000, help="samples per albedo point")
    parser.add_argument("--alpha", type=float, default=0.3)
    args = parser.parse_args()

    theta = np.radians(np.linspace(0, 85, 300))
    mus = np.linspace(0.02, 1, 40)
    rng = np.random.default_rng(7)
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for label, ndf in NDFS:
        d_kernel = kernel(ndf, "none")
        w = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)
        D = 4 * d_kernel.eval(w, w, alpha=args.alpha)[:, 0] * np.cos(theta) ** 2
        left.semilogy(np.degrees(theta), D, label=label)

        e_kernel = kernel(ndf, "smith_height_correlated")
        albedo = []
        for mu in mus:
            wo = np.array([np.sqrt(1 - mu * mu), 0.0, mu])
            u = rng.random((args.samples, 3), dtype=np.float32)
            _, _, weight = e_kernel.sample(wo, u, alpha=args.alpha)
            albedo.append(weight[:, 0].mean())
        right.plot(mus, albedo, label=label)
    left.set(xlabel="theta_h (degrees)", ylabel="D", title=f"distribution of normals, alpha = {args.alpha}")
    left.set_ylim(1e-4, None)
    right.set(xlabel="cos theta_o", ylabel="E", title="directional albedo (F = 1, Smith)", ylim=(0, 1.02))
    for ax in (left, right):
        ax.grid(alpha=0.3)
    right.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
