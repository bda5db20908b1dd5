"""``meshladar lrcs``: laser radar cross sections of a scene per view (and per part), printed
as a table and optionally written to CSV (:func:`meshladar.forward.lrcs.lrcs`)."""

from __future__ import annotations

import io

import numpy as np

from .._atomic_write import write_atomic
from ..errors import ParameterError
from ..forward.lrcs import lrcs
from ..meshes import fibonacci_sphere
from .checks import check_output
from .simulate import load_scene
from .words import flag_words

__all__ = ["cmd_lrcs", "lrcs_words"]

#: The translator of the API's messages into lrcs' flags (:func:`.words.flag_words`):
#: ``lrcs_words(message)`` names each option lrcs sets by its flag.
lrcs_words = flag_words({"ray_spacing": "--ray-spacing", "angles_deg": "--angles-deg",
                         "view_vectors": "--view-vectors", "per_part": "--per-part",
                         "bounces": "--bounces", "seed": "--seed", "views": "--views",
                         "normals": "--normals", "bounce_samples": "--bounce-samples"},
                        ("ray_spacing", "angles_deg", "view_vectors", "per_part",
                         "bounce_samples"))


def _views(args, scene):
    given = [f for f, v in (("--views", args.views), ("--angles-deg", args.angles_deg),
                            ("--view-vectors", args.view_vectors)) if v is not None]
    if len(given) > 1:
        raise ParameterError(f"give one of --views, --angles-deg and --view-vectors; got "
                             f"{' and '.join(given)}")
    if args.view_vectors is not None:
        if not scene.is_mesh:
            raise ParameterError("--view-vectors needs a mesh (a phantom is seen about z)")
        if args.elevation_deg is not None:
            raise ParameterError("--elevation-deg tilts the views of --views or "
                                 "--angles-deg; --view-vectors spreads its own over the "
                                 "sphere (leave out --elevation-deg)")
        return fibonacci_sphere(args.view_vectors)
    if args.angles_deg is not None:
        azimuth = np.asarray(args.angles_deg, dtype=np.float64)
    else:
        azimuth = np.arange(args.views or 36) * (360.0 / (args.views or 36))
    if args.elevation_deg is None:
        return azimuth
    if not scene.is_mesh:
        raise ParameterError("--elevation-deg needs a mesh (a phantom is seen about z)")
    az, el = np.radians(azimuth), np.radians(args.elevation_deg)
    return np.stack([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az),
                     np.full_like(az, np.sin(el))], axis=1)


def _table(result, views):
    """The CSV text: one row per view (its angle or vector), σ, dBsm, each part's σ."""
    out = io.StringIO()
    head = ["angle_deg"] if views.ndim == 1 else ["wx", "wy", "wz"]
    parts = [] if result.per_part is None else [f"sigma_{n}" for n in result.names]
    sampled = bool(np.any(result.stderr))            # orders beyond the first, sampled
    out.write(",".join(head + ["sigma"] + ["sigma_stderr"] * sampled + ["dbsm"] + parts)
              + "\n")
    for i, v in enumerate(views):
        row = [f"{x:.10g}" for x in np.atleast_1d(v)]
        row += [f"{result.values[i]:.10g}"] + [f"{result.stderr[i]:.3g}"] * sampled
        row += [f"{result.dbsm[i]:.10g}"]
        if result.per_part is not None:
            row += [f"{x:.10g}" for x in result.per_part[i]]
        out.write(",".join(row) + "\n")
    return out.getvalue()


def cmd_lrcs(args) -> int:
    """Laser radar cross sections of a scene (a mesh file or a phantom) from each view:
    sigma = 4 pi x the power returned toward the receiver per unit solid angle per unit
    incident irradiance, in square scene units (a phantom's per unit height), with dBsm;
    --per-part adds each part's share, --bounces the orders beyond the first (mesh;
    sampled: a sigma_stderr column gives each sigma's standard error, which
    --bounce-samples lowers). --quiet prints the table alone, and nothing with -o.

    Parameters
    ----------
    args : argparse.Namespace
        ``scene``, ``material``, ``coating``, ``materials`` (as ``simulate``'s);
        ``views``, ``angles_deg`` or ``view_vectors``; ``elevation_deg`` (the views of
        ``views`` or ``angles_deg`` raised above the x-y plane); ``bounces``, ``bounce_samples``,
        ``per_part``, ``ray_spacing``, ``seed``, ``normals``, ``output`` (CSV or None) and
        ``quiet``.

    Returns
    -------
    int
        0, the exit status.
    """
    if args.output is not None:
        check_output(args.output, (".csv",), [args.scene, args.materials])
    scene, _, _ = load_scene(args)
    if args.normals is not None and not scene.is_mesh:
        raise ParameterError("--normals shades a mesh's faces; a phantom's cross sections "
                             "come from its exact shapes (leave out --normals)")
    views = _views(args, scene)
    options = {k: getattr(args, k) for k in ("ray_spacing", "seed", "normals",
                                             "bounce_samples")
               if getattr(args, k) is not None}
    result = lrcs(scene, views, bounces=args.bounces, per_part=args.per_part, **options)
    text = _table(result, views)
    if args.output is not None:
        write_atomic(args.output, lambda fh: fh.write(text.encode()))
    if not args.quiet:
        print(f"# laser radar cross section, {result.units} (the scene's length unit: m^2 "
              f"and dBsm for metres), {result.bounces} "
              f"bounce{'s' if result.bounces > 1 else ''}; {result.convention}")
    if not args.quiet or args.output is None:     # the table is the result: --quiet
        print(text, end="")                          # keeps it where it is not written
    return 0
