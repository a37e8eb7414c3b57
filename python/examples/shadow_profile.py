"""A shadow profile across a baked PDSM, plotted with matplotlib (docs/python.md).

    PYTHONPATH=build/python python3 python/examples/shadow_profile.py OUT.exr profile.png

Samples the attenuation of every light of the file along a line on the ground (y = 0, from
x = -10 to 10 at z = 0) and plots one curve per light.
"""

import sys

import matplotlib.pyplot as plt
import numpy as np

import pdsm


def main(pdsm_path, png_path):
    f = pdsm.open(pdsm_path)
    x = np.linspace(-10, 10, 801)
    points = np.column_stack([x, np.zeros_like(x), np.zeros_like(x)])
    fig, ax = plt.subplots(figsize=(8, 3))
    for index, name in enumerate(f.lights):
        ax.plot(x, f.attenuation(points, light=index), label=name or "light")
    ax.set_xlabel("x (world units), on the ground at z = 0")
    ax.set_ylabel("fraction of the light hidden")
    ax.set_ylim(-0.05, 1.05)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png_path, dpi=100)


if __name__ == "__main__":
    main(*sys.argv[1:3])
