"""A convergence study: the error of the `simple-diffuse` scene against a reference, as rendering
time goes on, with next-event estimation on and off, plotted on log-log axes (matplotlib).

    python examples/convergence.py -o convergence.png [--size 160x90] [--spp 256] [--device auto]
"""

import argparse
import sys

import numpy as np

import pathtrace
from pathtrace.cli.options import image_size


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])   # the first paragraph, whole
    parser.add_argument("-o", "--output", default="convergence.png")
    parser.add_argument("--size", default="160x90", type=image_size, help="WxH")
    parser.add_argument("--spp", type=int, default=256, help="samples of the longest run")
    parser.add_argument("--device", default="auto")
    args = parser.parse_args()
    size = args.size
    try:                    # after the arguments, so that --help needs no matplotlib
        import matplotlib
    except ImportError:
        sys.exit("convergence.py: the plot needs matplotlib, which pathtrace does not install: "
                 ".venv/bin/python -m pip install matplotlib")
    matplotlib.use("Agg")           # files only, no window
    import matplotlib.pyplot as plt

    scene = pathtrace.load("simple-diffuse")
    # the reference: 8x the samples, with NEE and another seed, so that its noise is not the runs'
    reference = pathtrace.render(scene, spp=8 * args.spp, size=size, device=args.device, nee=True, seed=1)
    for nee in (False, True):
        runs = pathtrace.progressive(scene, spp=args.spp, size=size, device=args.device, nee=nee)
        points = [(s.seconds, float(np.sqrt(np.mean((s.image - reference) ** 2)))) for s in runs]
        seconds, rmse = zip(*points)
        plt.loglog(seconds, rmse, "o-", label="NEE + MIS" if nee else "BSDF sampling only")
        print(f"nee={nee}: RMSE {rmse[-1]:.4g} after {seconds[-1]:.3g} s")
    plt.xlabel("rendering time (s)")
    plt.ylabel("RMSE against the reference")
    plt.title(f"simple-diffuse, {size[0]}x{size[1]}")
    plt.legend()
    plt.grid(True, which="both", alpha=0.3)
    plt.tight_layout()               # the axis labels inside the figure
    plt.savefig(args.output, dpi=100)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    try:
        main()
    except pathtrace.UserError as e:       # one line, as pathtrace's own commands say it
        sys.exit(f"{__file__.rpartition('/')[2]}: error: {e}")
