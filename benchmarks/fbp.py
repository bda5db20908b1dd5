"""Filtered backprojection against scikit-image's ``iradon`` on the same 360 × 1024
sinogram into a 1024² image, one thread, in interleaved rounds timed in CPU seconds (robust
to a loaded machine): the figure of ``meshladar bench``'s FBP line, and the backprojection
loop alone.

    taskset -c 0 python benchmarks/fbp.py [--rounds 5] [--size 1024] [--bins 1024]

Prints millions of pixel-views (pixels × views) per CPU second of each, the median of the
rounds' ratios, the largest difference of the two images, the backprojection loop alone
(each view on its own, linear and nearest-sample, and with the views 180° apart folded
into one, as ``meshladar.fbp`` runs it), and the SIMD registers of the loop's gathers when
it was compiled in this process.
"""

from __future__ import annotations

import argparse
import re
import statistics
import time

import numba
import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--bins", type=int, default=1024)
    args = ap.parse_args(argv)

    from meshladar.reconstruct._folded import backproject_views
    from meshladar.reconstruct._kernels import backproject
    from meshladar.studies.timing import interleaved_times
    from meshladar.studies.bench import bench_fbp

    numba.set_num_threads(1)
    r = bench_fbp(n_bins=args.bins, size=args.size, repeats=args.rounds)
    pv = 360.0 * args.size ** 2
    print(f"FBP 360 x {args.bins} -> {args.size}^2, ramp, linear, one thread, median of "
          f"{args.rounds} interleaved rounds, CPU seconds")
    print(f"  meshladar.fbp  {r['ours_s']:.3f} s  {r['mpix_views']:7.0f} Mpixel-views/s")
    print(f"  skimage.iradon {r['skimage_s']:.3f} s  {r['skimage_mpix_views']:7.0f} "
          f"Mpixel-views/s")
    print(f"  speed-up {r['speedup']:.2f}x (median of the rounds' ratios); max |difference| "
          f"{r['max_diff_rel']:.1e} of the image maximum")

    rng = np.random.default_rng(0)
    q = rng.normal(size=(360, args.bins))
    phi = np.deg2rad(np.arange(360.0))
    c, s, w = np.cos(phi), np.sin(phi), np.full(360, np.pi / 360)
    x = (np.arange(args.size) - args.size / 2 + 0.5) * 2.0 / args.size
    out = np.zeros((args.size, args.size))
    dr_inv, r0 = args.bins / 2.0, -1.0 + 1.0 / args.bins

    def loop(nearest):
        return lambda: backproject(q, c, s, w, r0, dr_inv, x, x, nearest, out)

    def folded():
        return backproject_views(q, np.arange(360.0), w, r0, dr_inv, x, x, False, out)

    t = interleaved_times({"linear": loop(False), "nearest": loop(True), "folded": folded},
                          repeats=args.rounds, clock=time.process_time)
    for k, v in t.items():
        print(f"  backprojection loop alone, {k:7s} {statistics.median(v):.3f} s  "
              f"{pv / statistics.median(v) / 1e6:7.0f} Mpixel-views/s")
    print(f"  gathers in the compiled row loop: {_gathers()}")


def _gathers():
    """The vector registers the gathers of the row loop's machine code load ("ymm": 4
    doubles, "zmm": 8), or why they are not known."""
    from meshladar.reconstruct import _kernels

    row = getattr(_kernels, "_backproject_row", None)
    if row is None:
        return "no row loop (the per-pixel kernel)"
    asm = "\n".join(row.inspect_asm(sig) for sig in row.signatures)
    if not asm.strip():                          # loaded from numba's cache: no assembly
        return "unknown (loaded from numba's cache; set NUMBA_CACHE_DIR to an empty folder)"
    regs = sorted(set(re.findall(r"vgather\w+\s+[^(\n]*\([^)]*\),\s*%([xyz]mm)", asm)))
    return ", ".join(regs) if regs else "none (not vectorised)"


if __name__ == "__main__":
    main()
