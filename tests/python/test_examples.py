"""The examples under examples/python run and write their pictures (small
settings; the README's pictures are the same scripts at their defaults)."""

import os
import subprocess
import sys

import numpy as np
import matplotlib.image

from conftest import SOURCE

EXAMPLES = os.path.join(SOURCE, "examples", "python")


def run(script, *args):
    out = subprocess.run([sys.executable, os.path.join(EXAMPLES, script), *args], capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_plot_ndfs(tmp_path):
    png = tmp_path / "ndfs.png"
    assert "wrote" in run("plot_ndfs.py", str(png), "--samples", "4000")
    image = matplotlib.image.imread(png)
    assert image.shape[0] > 300 and image.shape[1] > 800
    assert image[..., :3].std() > 0.05  # curves, not a blank canvas


def test_render_sphere(tmp_path):
    png = tmp_path / "spheres.png"
    assert "wrote" in run("render_sphere.py", str(png), "--size", "48", "--spp", "8")
    image = matplotlib.image.imread(png)[..., :3]
    assert image.shape == (48, 4 * 48, 3)
    centre = image[24, 24]  # the plastic sphere: red
    assert centre[0] > centre[1] + 0.1 and centre[0] > centre[2] + 0.1
    assert np.isfinite(image).all() and image.max() > 0.5


def test_call_overhead_prints_both_sizes():
    out = run("call_overhead.py")
    lines = [l for l in out.splitlines() if l.split() and l.split()[0] in ("1", "65536")]
    assert len(lines) == 2
