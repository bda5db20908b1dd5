"""The ``meshladar`` command line.

Errors from bad input print one line (``meshladar: error: ...``) and exit with status 2;
they never show a traceback.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

from .errors import MeshladarError

__all__ = ["main"]

_DEMO_ANGLES_DEG = (0.0, 1.0, 5.0, 10.0, 30.0, 60.0, 85.0, 90.0)


def _cmd_demo(args) -> int:
    """Print the paper's two coatings' monostatic BRDF at a few incidence angles."""
    from . import materials

    angles = np.array(args.angles_deg, dtype=np.float64)
    theta = np.deg2rad(angles)
    print("Sandford-Robertson BRDF, monostatic (collocated ladar), paper coatings at 1 um")
    for m in (materials.DARK_GRAY, materials.ALUMINUM):
        print(f"\n{m.name}: rho_d={m.rho_d:g} epsilon={m.epsilon:g} b={m.b:g} e={m.e:g}"
              f"  G(b)={m.G:.6f}")
        print(f"  {'theta [deg]':>11}  {'F [1/sr]':>12}  {'F cos(theta) [1/sr]':>20}"
              f"  {'rho_s(theta)':>12}")
        f = m.monostatic(theta)
        fc = m.monostatic(theta, projected=True)
        rs = m.specular_reflectance(theta)
        for row in zip(angles, f, fc, rs):
            print(f"  {row[0]:11.3f}  {row[1]:12.6g}  {row[2]:20.6g}  {row[3]:12.6f}")
    return 0


def _cmd_materials(args) -> int:
    """List a coating table (the packaged one by default)."""
    from . import materials

    if args.table is None:
        from meshladar.phantoms import materials as packaged

        table = packaged()
    else:
        table = materials.load_table(args.table)
    print(f"{'name':<14} {'lobes':<9} {'rho_d':>7} {'epsilon':>8} {'b':>6} {'e':>7}"
          f" {'G(b)':>8} {'F(0) [1/sr]':>12}")
    for name, m in table.items():
        print(f"{name:<14} {m.lobes:<9} {m.rho_d:7.4g} {m.epsilon:8.4g} {m.b:6.4g} {m.e:7.4g}"
              f" {m.G:8.5f} {m.monostatic(0.0):12.5g}")
    return 0


def _cmd_paper(args) -> int:
    """Reproduce the paper's Figs 5-11: PNGs, a saved result and the findings' numbers."""
    from meshladar.viz import paper

    paths, metrics = paper.reproduce(args.outdir, size=args.size)
    print(f"Jin & Levine (2009) Figs 5-11 reproduced in {args.outdir}/ "
          "(analytic model, 360 views, A/256 bins)")
    print(f"  {'finding':<42} {'value':>10}")
    for key, value in metrics.items():
        print(f"  {key:<42} {value:10.4f}")
    for p in paths:
        print(f"  wrote {p}")
    return 0


def _cmd_study(args) -> int:
    """Run a study and write its table (CSV/JSON), results and figures into a folder."""
    from . import studies
    from meshladar.viz import studies as vstudies

    result = studies.faceting_study(args.setting, progress=not args.quiet)
    files = studies.save_study(result, args.outdir)
    figs = vstudies.draw(args.outdir)
    print(studies.report(result))
    for p in files + figs:
        print(f"  wrote {p}")
    return 0


def _cmd_bench(args) -> int:
    """Time the forward models and FBP against their peers (median of several runs)."""
    from .bench import bench_analytic

    print(f"analytic model, 360 views x 512 bins (A/256), median of {args.repeats} runs "
          "after one warm-up")
    print(f"  {'case':<40} {'median [s]':>10} {'min [s]':>9} {'max [s]':>9}")
    for row in bench_analytic(repeats=args.repeats):
        print(f"  {row['case']:<40} {row['median_s']:10.3f} {row['min_s']:9.3f} "
              f"{row['max_s']:9.3f}")
    from .bench import bench_fbp

    try:
        r = bench_fbp(repeats=args.repeats)
    except ImportError as exc:
        print(f"FBP vs scikit-image: skipped ({exc})")
        return 0
    print(f"FBP {r['shape'][0]} x {r['shape'][1]} -> {r['size']}^2, ramp, linear: "
          f"meshladar {r['ours_s']:.3f} s, skimage.iradon {r['skimage_s']:.3f} s, "
          f"speed-up {r['speedup']:.1f}x, max |difference| {r['max_diff_rel']:.1e} of max")
    from .bench import bench_mesh, bench_streaming

    m = bench_mesh(repeats=args.repeats)
    print(f"mesh engine, {m['faces']} triangles, {m['views']} views x "
          f"{m['rays'] // m['views']} rays (3-D grid), same rays in the same process:")
    print(f"  raw embreex cast (output=1)       {m['raw_mrays']:7.2f} Mrays/s")
    print(f"  pipeline, 1 process               {m['pipeline_mrays']:7.2f} Mrays/s "
          f"({100 * m['pipeline_over_raw']:.0f}% of raw)")
    print(f"  pipeline, 2 processes             {m['two_core_mrays']:7.2f} Mrays/s "
          f"({m['two_over_one']:.2f}x one)")
    print(f"  Embree build, {m['build_faces']} triangles: embreex upload {m['upload_s']:.2f} s "
          f"+ BVH {m['bvh_s']:.2f} s = {m['build_over_bvh']:.1f}x the BVH build")
    if args.full:
        st = bench_streaming()
        print(f"streaming 360 views x 1e6 rays, 2 processes: {st['seconds']:.1f} s, "
              f"{st['mrays']:.2f} Mrays/s, peak RSS {st['peak_rss_mb']:.0f} MB")
    return 0


def _positive_int(text: str):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a positive integer; got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer; got {text!r}")
    return value


def _angle_list(text: str):
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be comma-separated numbers in degrees; got {text!r}") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"must be finite numbers in degrees; got {text!r}")
    return values


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="meshladar",
        description="Mesh-based ladar simulation and reflection tomography.",
        epilog="examples:\n  meshladar demo\n  meshladar demo --angles-deg 0,2,4\n"
               "  meshladar materials\n  meshladar materials my_coatings.toml\n"
               "  meshladar paper paper-figures/\n  meshladar study faceting study/\n"
               "  meshladar bench",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    d = sub.add_parser("demo", help="print the paper's coatings' monostatic BRDF",
                       description=_cmd_demo.__doc__,
                       epilog="example:\n  meshladar demo --angles-deg 0,1,5,45,90",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    d.add_argument("--angles-deg", type=_angle_list,
                   default=list(_DEMO_ANGLES_DEG),
                   help="incidence angles in degrees, comma-separated (default: %(default)s)")
    d.set_defaults(func=_cmd_demo)
    m = sub.add_parser("materials", help="list a coating table",
                       description=_cmd_materials.__doc__,
                       epilog="examples:\n  meshladar materials\n  meshladar materials mine.toml",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    m.add_argument("table", nargs="?", default=None,
                   help="a TOML material table (default: the packaged paper coatings)")
    m.set_defaults(func=_cmd_materials)
    pp = sub.add_parser("paper", help="reproduce the paper's Figs 5-11 into a folder",
                        description=_cmd_paper.__doc__,
                        epilog="example:\n  meshladar paper paper-figures/",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    pp.add_argument("outdir", help="folder for the PNGs and paper_result.npz")
    pp.add_argument("--size", type=_positive_int, default=512,
                    help="reconstruction size in pixels (default: %(default)s)")
    pp.set_defaults(func=_cmd_paper)
    st = sub.add_parser("study", help="faceting-vs-analytic study into a folder",
                        description=_cmd_study.__doc__,
                        epilog="examples:\n  meshladar study faceting study/\n"
                               "  meshladar study faceting study-full/ --full",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    st.add_argument("kind", choices=["faceting"], help="which study")
    st.add_argument("outdir", help="folder for faceting.csv/json, results and figures")
    st.add_argument("--full", dest="setting", action="store_const", const="full",
                    default="quick", help="the full sweep (360 views, segments to 4096)")
    st.add_argument("--quiet", action="store_true", help="no progress bar")
    st.set_defaults(func=_cmd_study)
    bch = sub.add_parser("bench", help="time the forward models (median of several runs)",
                         description=_cmd_bench.__doc__,
                         epilog="example:\n  meshladar bench --repeats 7",
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    bch.add_argument("--repeats", type=_positive_int, default=5,
                     help="timed runs per case after one warm-up (default: %(default)s)")
    bch.add_argument("--full", action="store_true",
                     help="also the streaming run: 360 views x 1e6 rays (about a minute)")
    bch.set_defaults(func=_cmd_bench)
    return p


def main(argv=None) -> int:
    """Run the command line; returns the exit status."""
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except MeshladarError as exc:
        print(f"meshladar: error: {exc}", file=sys.stderr)
        return 2
