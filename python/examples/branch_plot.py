"""Read a tmrotor recording, print its stable/unstable counts and plot the RMS amplitude of
one dynamic node against omega (matplotlib, if installed).

    python examples/branch_plot.py sweep.mcap [--node 8] [-o branch.png]
"""

from __future__ import annotations

import argparse
import sys

import tmrotor


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording")
    parser.add_argument("--node", type=int, help="dynamic node id (default: the first)")
    parser.add_argument("-o", "--output", help="PNG to write (default: <recording>_node<id>.png)")
    args = parser.parse_args()

    rec = tmrotor.read(args.recording)
    b = rec.branch
    stable = int(b["stable"].eq(True).sum())
    unstable = int(b["stable"].eq(False).sum())
    print(
        f"{rec.path.name}: {len(b)} points, {stable} stable, {unstable} unstable, "
        f"{len(b) - stable - unstable} not assessed"
    )
    if not rec.info["complete"]:
        print("incomplete recording: " + "; ".join(rec.info["notes"]))
    for row in rec.bifurcations.itertuples():
        print(f"  {row.type} at ω = {row.omega_rad_s:.4f} rad/s (after point {row.after_point})")

    node = args.node if args.node is not None else rec.run_info.nodes[0].id
    column = f"amp_rms_node{node}_m"
    if column not in b.columns:
        print(f"no dynamic node {node}; nodes: {[n.id for n in rec.run_info.nodes]}")
        return 1
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: no plot")
        return 0

    amp_um = b[column] * 1e6
    bad = b["stable"].eq(False).fillna(False).to_numpy(dtype=bool)
    fig, ax = plt.subplots(figsize=(7, 4))
    # the line follows the branch in point order, so folds are drawn as they are
    ax.plot(b["omega_rad_s"], amp_um, "-", color="tab:blue", lw=1.2, label="branch")
    ax.plot(b["omega_rad_s"][bad], amp_um[bad], "x", color="tab:red", label="unstable")
    ax.set_xlabel("ω (rad/s)")
    ax.set_ylabel(f"RMS amplitude node {node} (µm)")
    ax.set_title(rec.path.name)
    ax.legend()
    ax.grid(alpha=0.3)
    out = args.output or f"{rec.path.name.split('.')[0]}_node{node}.png"
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
