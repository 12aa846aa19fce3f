"""Work-precision plot of flexmbs-bench-mexax-control's table: per chain
length, the largest relative angle error at t = 1 against the function
evaluations (NFCN), one line per base method and control, TOL 1e-3 to 1e-9
along each line, and the 20 TOL mark of each TOL as a dotted guide.

Usage: python3 bench/mexax_control_plot.py TABLE PNG
"""
import collections
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402


def read(path):
    runs = collections.defaultdict(list)
    with open(path) as table:
        for line in table:
            words = line.split()
            if len(words) != 11 or words[0] != "wp" or words[1] == "base":
                continue
            base, control, bars = words[1], words[2], int(words[3])
            tol, nfcn, ratio = float(words[4]), int(words[8]), float(words[9])
            runs[(bars, base, control)].append((tol, nfcn, ratio * tol))
    return runs


def main(table, png):
    runs = read(table)
    if not runs:
        sys.exit(f"{table}: no 'wp' rows")
    chains = sorted({key[0] for key in runs})
    fig, axes = plt.subplots(1, len(chains), figsize=(3.2 * len(chains), 3.4), sharey=True)
    if len(chains) == 1:
        axes = [axes]
    styles = {("euler", "hairer"): ("C0", "--"), ("euler", "deuflhard"): ("C0", "-"),
              ("midpoint", "hairer"): ("C1", "--"), ("midpoint", "deuflhard"): ("C1", "-")}
    for ax, bars in zip(axes, chains):
        for (base, control), (colour, dash) in styles.items():
            points = sorted(runs.get((bars, base, control), []))
            if not points:
                continue
            ax.loglog([p[1] for p in points], [p[2] for p in points], dash, color=colour,
                      marker="o", markersize=3, label=f"{base}, {control}")
        tols = sorted({p[0] for key, pts in runs.items() if key[0] == bars for p in pts})
        for tol in tols:
            ax.axhline(20 * tol, color="0.8", linestyle=":", linewidth=0.8)
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title(f"{bars} bars")
        ax.set_xlabel("NFCN")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("max |dphi/phi| at t = 1")
    axes[-1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    print(f"wrote {png}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
