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
from .forward import MODELS
from .ladar import MAX_VIEWS as _MAX_VIEWS
from .reconstruct import FILTERS
from .sensor import RADIOMETRIES
from .raytrace import BACKENDS, MODES, NORMALS, SAMPLINGS

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
    from ._validate import check_size

    _check_outdir(args.outdir)
    check_size("--size", float(args.size) ** 2, 8 * 3, f"a {args.size} x {args.size} image",
               "use a smaller --size")
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


def _check_outdir(outdir):
    """An output folder: a folder (existing or not), not a file, not empty."""
    import os

    from .errors import ParameterError

    if not outdir or (os.path.exists(outdir) and not os.path.isdir(outdir)):
        raise ParameterError(f"outdir must name a folder; got {outdir!r}"
                             + (" (a file)" if outdir and os.path.exists(outdir) else ""))


def _coatings(text):
    """'part=name,part=name' → dict (names from the coating table)."""
    out = {}
    for item in filter(None, (x.strip() for x in text.split(","))):
        if "=" not in item:
            raise argparse.ArgumentTypeError(f"must be PART=COATING pairs; got {item!r}")
        k, v = item.split("=", 1)
        out[k.strip()] = v.strip()
    return out


#: What the command line calls resolve()'s arguments, in its errors.
_SCENE_LABELS = {"source": "SCENE", "material": "--material", "coatings": "--coating"}


def _load_scene(args):
    """(scene, default ladar or None, default model) from SCENE: phantom, spec or mesh
    (:func:`meshladar.phantoms.resolve`)."""
    from meshladar import phantoms

    return phantoms.resolve(args.scene, material=args.material, coatings=args.coating,
                            materials_file=args.materials, labels=_SCENE_LABELS)


def _ladar(args, scene, default):
    from .ladar import Ladar
    from .mesh import fibonacci_sphere

    from .errors import ParameterError

    for flag, n in (("--views", args.views), ("--view-vectors", args.view_vectors)):
        if n is not None and n > _MAX_VIEWS:
            raise ParameterError(f"{flag}: at most {_MAX_VIEWS:.0e} views; got {n}")
    vectors = None if args.view_vectors is None else fibonacci_sphere(args.view_vectors)
    angles = args.angles_deg if args.angles_deg is not None else (
        np.arange(args.views) * (360.0 / args.views) if args.views else None)
    if args.bins or args.bin_width:
        return Ladar.covering(scene, n_bins=args.bins, bin_width=args.bin_width,
                              angles_deg=angles, view_vectors=vectors)
    if default is not None and vectors is None:
        return default if angles is None else Ladar(angles, default.bin_edges)
    return Ladar.covering(scene, n_bins=512, angles_deg=angles, view_vectors=vectors)


#: simulate's sensor options (flag, attribute): the mesh model's ``sensor``.
_SENSOR_FLAGS = (("--standoff", "standoff"), ("--beam-waist", "beam_waist"),
                 ("--beam-divergence", "beam_divergence"), ("--beam-offset", "beam_offset"),
                 ("--flood-radius", "flood_radius"), ("--pulse-energy", "pulse_energy"),
                 ("--aperture", "aperture"), ("--extinction", "extinction"),
                 ("--wavelength", "wavelength"),
                 ("--optics-transmission", "optics_transmission"),
                 ("--quantum-efficiency", "quantum_efficiency"))


def _sensor(args):
    """The Sensor simulate's options describe, or None when none is given."""
    from .errors import ParameterError
    from .sensor import FloodBeam, GaussianBeam, Sensor

    if all(getattr(args, a) is None for _, a in _SENSOR_FLAGS):
        return None
    gaussian = [f for f, a in _SENSOR_FLAGS[1:4] if getattr(args, a) is not None]
    if gaussian and args.beam_waist is None:
        raise ParameterError(f"{gaussian[0]} shapes a Gaussian beam: give --beam-waist too")
    if gaussian and args.flood_radius is not None:
        raise ParameterError("--flood-radius and --beam-waist both choose the beam; give one")
    if args.beam_waist is not None:
        beam = GaussianBeam(args.beam_waist, divergence=args.beam_divergence or 0.0,
                            offset=args.beam_offset or (0.0, 0.0))
    else:
        beam = FloodBeam(args.flood_radius)
    kw = {k: getattr(args, a) for k, a in (("standoff", "standoff"), ("extinction",
          "extinction"), ("pulse_energy", "pulse_energy"), ("aperture_diameter", "aperture"),
          ("wavelength", "wavelength"), ("optics_transmission", "optics_transmission"),
          ("quantum_efficiency", "quantum_efficiency")) if getattr(args, a) is not None}
    return Sensor(beam=beam, **kw)


#: simulate's options that only the mesh model reads (flag -> attribute).
_MESH_ONLY = {"--mode": "mode", "--z0": "z0", "--normals": "normals",
              "--ray-spacing": "ray_spacing", "--rays-per-bin": "rays_per_bin",
              "--sampling": "sampling", "--seed": "seed", "--footprint": "footprint",
              "--receiver": "receiver", "--tol": "tol", "--max-rays": "max_rays",
              "--backend": "backend", **{f: a for f, a in _SENSOR_FLAGS}}


def _check_applicable(args, model, is_phantom):
    """Options that do not apply to this run are errors, never silently ignored."""
    from .errors import ParameterError

    def given(attr):
        v = getattr(args, attr)
        return v is not None and v is not False

    exclusive = [("--views", "views"), ("--angles-deg", "angles_deg"),
                 ("--view-vectors", "view_vectors")]
    named = [flag for flag, attr in exclusive if given(attr)]
    if len(named) > 1:
        raise ParameterError(f"{named[0]} and {named[1]} both choose the views; give one")
    if model != "mesh":
        for flag, attr in _MESH_ONLY.items():
            if given(attr):
                raise ParameterError(f"{flag} is an option of the mesh model; the {model} "
                                     "model does not use it (add --model mesh)")
    if model != "pixel" and given("pixel_size"):
        raise ParameterError(f"--pixel-size is an option of the pixel model; the {model} "
                             "model does not use it (add --model pixel)")
    if given("segments") and not (is_phantom and model == "mesh"):
        raise ParameterError("--segments tessellates an analytic phantom for --model mesh; "
                             "it does not apply here")
    if given("z0") and args.mode != "slice" and not (is_phantom and args.mode is None):
        raise ParameterError("--z0 places the slice plane: it needs --mode slice")
    if given("seed") and args.sampling == "regular":
        raise ParameterError("--seed jitters the rays: it needs --sampling stratified, not "
                             "regular")
    if given("max_rays") and not given("tol"):
        raise ParameterError("--max-rays bounds the work of --tol; give --tol too")
    if given("jobs") and (given("scheduler") or given("workers")):
        raise ParameterError("--jobs runs local processes; with --scheduler or --workers "
                             "Dask runs the work: give one")


def _summary(args, sino, ladar, model):
    """One line: what was simulated, how (mode, normals, sampling, rays, bins) and where."""
    info = sino.info
    how = f"{model} model"
    if model == "mesh":
        rec = info.get("receiver")
        how += (f", {info.get('mode')} mode, {info.get('normals')} normals, "
                f"{info.get('sampling')} sampling, ray spacing {info.get('ray_spacing'):.4g}, "
                f"{'footprint' if info.get('footprint') else 'point'} bins, "
                + ("monostatic" if rec is None else "bistatic receiver") + ", "
                f"{info.get('rays', 0):,} rays cast ({info.get('backend')} backend)")
        if info.get("mode") == "slice":
            how += f" (values per unit height at z0 = {info.get('z0'):g})"
        if "error_estimate" in info:
            how += f", estimated error {info['error_estimate']:.2g}"
    return (f"{args.scene}: {how}; {ladar.n_views} views x {ladar.n_bins} bins over range "
            f"[{ladar.bin_edges[0]:.6g}, {ladar.bin_edges[-1]:.6g}] (range 0 on the plane "
            f"through the origin facing the ladar); {info.get('radiometry', 'paper')} "
            f"radiometry; total return per view {sino.total().mean():.6g}; wrote "
            f"{args.output}")


def _cmd_simulate(args) -> int:
    """Simulate a scene's range profiles and save them (sinogram, scene, parameters)."""
    from . import results
    from .forward import simulate

    _check_output(args.output, (".npz",), [args.scene, args.materials, args.run_dir])
    scene, default_ladar, default_model = _load_scene(args)
    model = args.model or default_model
    _check_applicable(args, model, default_ladar is not None)
    ladar = _ladar(args, scene, default_ladar)
    opts = {}
    if model == "mesh":
        if not scene.is_mesh and args.tol is None:       # with --tol the knob tessellates
            scene = scene.tessellate(args.segments or 1024)
        for k in ("mode", "z0", "normals", "ray_spacing", "rays_per_bin", "sampling", "seed",
                  "tol", "max_rays", "receiver", "backend"):
            if getattr(args, k) is not None:
                opts[k] = getattr(args, k)
        if args.footprint:
            opts["footprint"] = True
        sensor = _sensor(args)
        if sensor is not None:
            opts["sensor"] = sensor
    elif model == "pixel" and args.pixel_size is not None:
        opts["pixel_size"] = args.pixel_size
    if args.radiometry is not None:
        opts["radiometry"] = args.radiometry
    opts["jobs"] = args.jobs                 # the stream's options: every model takes them
    if args.run_dir is not None:
        opts["run_dir"] = args.run_dir
    opts["progress"] = not args.quiet
    if args.scheduler or args.workers:
        from .stream import dask_executor

        with dask_executor(args.scheduler, workers=args.workers or 2) as ex:
            sino = simulate(scene, ladar, model=model, executor=ex,
                            **{k: v for k, v in opts.items() if k != "jobs"})
    else:
        sino = simulate(scene, ladar, model=model, **opts)
    params = {"scene": args.scene, "model": model,
              "options": {k: (v.describe() if k == "sensor" else v) for k, v in opts.items()
                          if k != "progress"},
              "n_views": ladar.n_views, "n_bins": ladar.n_bins}
    results.save_sinogram(args.output, sino, scene=scene, params=params)
    if not args.quiet:
        print(_summary(args, sino, ladar, model))
    return 0


def _check_output(output, suffixes, inputs, flag="-o"):
    """An output path must never name an input, and must name a file of a known format."""
    import os

    from .errors import ParameterError

    if not output or os.path.basename(output) in ("", ".", "..") or os.path.isdir(output):
        raise ParameterError(f"{flag}: must name a file, not a folder; got {output!r}")
    for src in filter(None, inputs):
        if os.path.abspath(src) == os.path.abspath(output) or (
                os.path.exists(src) and os.path.exists(output)
                and os.path.samefile(src, output)):
            raise ParameterError(f"{flag} {output!r} is the input {src!r}: meshladar never "
                                 "overwrites an input; choose another output name")
    ext = os.path.splitext(output)[1].lower()
    if ext not in suffixes:
        raise ParameterError(f"{flag}: the extension decides the format: one of "
                             f"{', '.join(suffixes)}; got {output!r}")


#: Image formats reconstruct writes (matplotlib's own writers; JPEG and TIFF through Pillow,
#: a dependency of matplotlib).
_IMAGE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".tif", ".tiff")


def _cmd_reconstruct(args) -> int:
    """Reconstruct a saved sinogram by FBP: a figure (PNG, PDF, SVG, JPEG or TIFF, chosen by
    the extension of -o) and the image's values in OUTPUT.image.npz."""
    import os

    from . import results
    from .errors import ParameterError
    from .reconstruct import clip_radiance, fbp, log_radiance

    _check_output(args.output, _IMAGE_SUFFIXES, [args.result])
    data = os.path.splitext(args.output)[0] + ".image.npz"
    if os.path.abspath(data) == os.path.abspath(args.result) or (
            os.path.exists(data) and os.path.samefile(data, args.result)):
        raise ParameterError(f"-o {args.output!r} would write the image data to "
                             f"{data!r}, the input: meshladar never overwrites an input; "
                             "choose another output name")
    sino, meta = results.load_sinogram(args.result)
    if args.log:
        sino = log_radiance(sino)
    if args.clip is not None:
        sino = clip_radiance(sino, threshold=args.clip)
    extent = args.extent or float(max(abs(sino.bin_edges[0]), abs(sino.bin_edges[-1])))
    if not sino.planar:
        # a margin, so that a target filling the bins does not sit on the cube's faces
        return _reconstruct_3d(args, sino, args.extent or 1.15 * extent)
    if args.smooth is not None:
        raise ParameterError("--smooth applies to 3-D views (radon3d); this sinogram's views "
                             "are about the z axis (use --filter)")
    image = fbp(sino, size=args.size or 512, extent=extent, filter=args.filter or "ramp")
    from meshladar.viz import quick

    # the quick look's symmetric scale, log input labelled as such, and a centre slice
    prep = sino.info.get("preprocess")
    fig = quick.image(image, title=f"FBP of {os.path.basename(args.result)}"
                      + (f", {prep}" if prep else "") + f" ({args.filter or 'ramp'} filter)")
    fmt = os.path.splitext(args.output)[1].lower().lstrip(".")
    results.write_atomic(args.output, lambda fh: fig.savefig(fh, format=fmt, dpi=150))
    results.save_result(data, {"image": image.values},
                   {"kind": "image", "extent": extent, "info": image.info,
                    "source": os.path.basename(args.result)})
    if not args.quiet:
        size = args.size or 512
        print(f"wrote {args.output} and {data} ({size}x{size}, extent {extent:g})")
    return 0


def _cmd_receive(args) -> int:
    """Turn a saved sinogram's range bins into digitised waveforms (two-way time, the
    transmitted pulse, the receiver's impulse response, the digitiser's rate), optionally
    with noise realisations (photon counting, speckle, background and dark counts, APD
    gain and excess noise, quantisation); save them, and a figure with --plot."""
    import os

    from . import results
    from .errors import ParameterError
    from .receiver import GaussianPulse, Noise, receive

    _check_output(args.output, (".npz",), [args.result])
    if args.plot is not None:
        _check_output(args.plot, (".png",), [args.result, args.output], "--plot")
    sino, _ = results.load_sinogram(args.result)
    if sino.info.get("radiometry") != "power" and not args.quiet:
        import warnings

        from .errors import MeshladarWarning

        warnings.warn(f"{args.result} holds {sino.info.get('radiometry', 'paper')!r} "
                      "radiometry (Eq. 8), not the power a receiver collects: simulate with "
                      "--radiometry power for a receiver's waveform", MeshladarWarning)
    if args.pulse_fwhm is not None and args.pulse_samples is not None:
        raise ParameterError("--pulse-fwhm and --pulse-samples both give the pulse; give one")
    if (args.pulse_samples is None) != (args.pulse_interval is None):
        raise ParameterError("--pulse-samples needs --pulse-interval (s between samples), "
                             "and the other way round")
    pulse = None if args.pulse_fwhm is None else GaussianPulse(args.pulse_fwhm)
    if args.pulse_samples is not None:
        from .receiver import SampledPulse

        pulse = SampledPulse(_read_samples(args.pulse_samples), args.pulse_interval)
    waves = receive(sino, sample_rate=args.sample_rate, pulse=pulse,
                    response=None if args.response_fwhm is None
                    else GaussianPulse(args.response_fwhm),
                    standoff=args.standoff, oversample=args.oversample)
    if args.scale is not None:
        waves = waves.scaled(args.scale)
    noise_flags = ("speckle_cells", "background_rate", "dark_rate", "excess_noise", "gain",
                   "bits", "full_scale", "seed")
    noise = draws = None
    if args.realisations is None:
        given = [a for a in noise_flags if getattr(args, a) is not None]
        if given:
            raise ParameterError(f"--{given[0].replace('_', '-')} shapes the noise: give "
                                 "--realisations N too")
    else:
        kw = {k: getattr(args, a) for k, a in (
            ("speckle_cells", "speckle_cells"), ("background_rate", "background_rate"),
            ("dark_rate", "dark_rate"), ("excess_noise_factor", "excess_noise"),
            ("gain", "gain"), ("bits", "bits"), ("full_scale", "full_scale"))
            if getattr(args, a) is not None}
        noise = Noise(**kw)
        draws = waves.realise(noise, args.realisations, seed=args.seed)
    params = {"source": os.path.basename(args.result), "seed": args.seed,
              "realisations": args.realisations}
    results.save_waveforms(args.output, waves, realisations=draws, noise=noise,
                           params=params)
    if args.plot is not None:
        from meshladar.viz import waveforms as wf

        wf.draw(waves, args.plot, realisations=draws, noise=noise)
    if not args.quiet:
        extra = "" if draws is None else f", {len(draws)} noise realisations"
        print(f"{args.result}: {waves.values.shape[0]} views x {waves.values.shape[1]} "
              f"samples at {args.sample_rate:g} Hz over two-way time "
              f"[{waves.time_edges[0]:.6g}, {waves.time_edges[-1]:.6g}] s, units "
              f"{waves.info.get('units')}{extra}; wrote {args.output}"
              + ("" if args.plot is None else f" and {args.plot}"))
    return 0


def _reconstruct_3d(args, sino, extent) -> int:
    """reconstruct for views over the sphere: the 3-D Radon inversion (meshladar.volume),
    three central slices as the figure, the volume in OUTPUT.volume.npz."""
    import os

    from . import results
    from .errors import ParameterError
    from .volume import radon3d

    if args.filter is not None:
        raise ParameterError("--filter applies to FBP of views about the z axis; 3-D views "
                             "are inverted with a second difference (use --smooth BINS)")
    size = args.size or 128
    vol = radon3d(sino, size=size, extent=extent, smooth=args.smooth or 0.0)
    data = os.path.splitext(args.output)[0] + ".volume.npz"
    if os.path.abspath(data) == os.path.abspath(args.result):
        raise ParameterError(f"-o {args.output!r} would write the volume to the input "
                             f"{data!r}; choose another output name")
    from meshladar.viz import quick

    fig = quick.volume(vol, title=f"3-D Radon inversion of {os.path.basename(args.result)} "
                                  f"({sino.n_views} views, {size}^3)")
    fmt = os.path.splitext(args.output)[1].lower().lstrip(".")
    results.write_atomic(args.output, lambda fh: fig.savefig(fh, format=fmt, dpi=150))
    results.save_result(data, {"values": vol.values, "x": vol.x, "y": vol.y, "z": vol.z},
                        {"kind": "volume", "info": vol.info,
                         "source": os.path.basename(args.result)})
    if not args.quiet:
        print(f"wrote {args.output} and {data} ({size}^3, extent {extent:g}, "
              f"{sino.n_views} views)")
    return 0


def _read_samples(path):
    """A pulse's samples from a text file: numbers separated by commas, spaces or newlines
    (# starts a comment)."""
    from .errors import ParameterError

    try:
        with open(path, encoding="utf-8") as fh:
            text = " ".join(line.split("#")[0] for line in fh)
        values = [float(x) for x in text.replace(",", " ").split()]
    except UnicodeDecodeError:
        raise ParameterError(f"--pulse-samples {path!r}: not a text file of numbers") from None
    except ValueError as exc:
        raise ParameterError(f"--pulse-samples {path!r}: {exc}") from None
    return values


def _window_size(text):
    """argparse type for WxH in pixels."""
    parts = text.lower().split("x")
    try:
        size = tuple(int(p) for p in parts)
    except ValueError:
        size = ()
    if len(size) != 2 or not all(1 <= n <= 16384 for n in size):
        raise argparse.ArgumentTypeError(
            f"{text!r} is not WIDTHxHEIGHT in pixels, each 1-16384 (e.g. 1200x900)")
    return size


def _cmd_view(args) -> int:
    """Show a scene in 3-D coloured by its return for one view (or save a screenshot)."""
    import os

    from .errors import ParameterError

    if args.screenshot is not None:
        _check_output(args.screenshot, (".png",), [args.scene, args.materials],
                      "--screenshot")
    scene, default_ladar, _ = _load_scene(args)
    if args.screenshot is None and not (os.environ.get("DISPLAY")
                                        or os.environ.get("WAYLAND_DISPLAY")):
        raise ParameterError("no display to open a window on: use --screenshot PNG")
    from meshladar.viz import viewer

    viewer.show_scene(scene, view_angle_deg=args.view_angle, ladar=default_ladar,
                      off_screen=args.screenshot is not None, screenshot=args.screenshot,
                      log_scale=args.log, window_size=args.size, camera=args.camera)
    if args.screenshot and not args.quiet:
        print(f"wrote {args.screenshot}")
    return 0


def _cmd_study(args) -> int:
    """Run a study and write its table (CSV/JSON), results and figures into a folder."""
    from . import studies
    from meshladar.viz import studies as vstudies

    import os

    _check_outdir(args.outdir)
    if args.kind == "tomography3d":
        return _study_3d(args)
    if args.kind == "reconstruction":
        return _study_reconstruction(args)
    for flag, value in (("--photons", args.photons), ("--speckle", args.speckle),
                        ("--background", args.background)):
        if value is not None:
            from .errors import ParameterError

            raise ParameterError(f"{flag} is an option of the reconstruction study; the "
                                 f"{args.kind} study does not use it")
    result = studies.faceting_study(args.setting, progress=not args.quiet,
                                    run_dir=os.path.join(args.outdir, "run"))
    files = studies.save_study(result, args.outdir)
    figs = vstudies.draw(args.outdir)
    print(studies.report(result))
    for p in files + figs:
        print(f"  wrote {p}")
    return 0


#: The 3-D study's settings: (views, voxels per side, smoothing in bins, rays per bin).
_STUDY_3D = {"quick": (600, 64, 1.0, 1.0), "full": (2000, 128, 1.0, 2.0)}


def _study_3d(args) -> int:
    """The paper's findings in 3-D (meshladar.paper.run_3d): metrics as JSON, central slices
    of every volume as a PNG."""
    import json
    import os

    from . import paper, results

    views, size, smooth, rpb = _STUDY_3D[args.setting]
    metrics, volumes = paper.run_3d(views=views, size=size, smooth=smooth,
                                    rays_per_bin=rpb)
    os.makedirs(args.outdir, exist_ok=True)
    doc = {"setting": args.setting, "views": views, "size": size, "smooth_bins": smooth,
           "rays_per_bin": rpb, "metrics": metrics}
    path = os.path.join(args.outdir, "tomography3d.json")
    results.write_text_atomic(path, json.dumps(doc, indent=2, sort_keys=True))
    from meshladar.viz import studies as vstudies

    (png,) = vstudies.draw_tomography3d(volumes, args.outdir, views, size)
    print(f"3-D tomography study ({args.setting}: {views} views, {size}^3 voxels)")
    for key, value in metrics.items():
        print(f"  {key:<42} {value:10.4f}")
    print(f"  wrote {path}\n  wrote {png}")
    return 0


def _study_reconstruction(args) -> int:
    """The reconstruction study (meshladar.study_reconstruction): its table as CSV and JSON,
    the 1° and 10° images of every method as a figure."""
    import csv
    import io
    import json
    import os

    from . import results, study_reconstruction as study

    rows, images = study.run(args.setting, photons=args.photons, speckle_cells=args.speckle,
                             background=args.background or 0.0)
    os.makedirs(args.outdir, exist_ok=True)
    path = os.path.join(args.outdir, "reconstruction.json")
    results.write_text_atomic(path, json.dumps({"setting": args.setting, "rows": rows},
                                               indent=2))
    buf = io.StringIO()
    keys = ["phantom", "spacing_deg", "method", "photons", "speckle_cells", "background",
            "error", "clutter", "darkening", "visibility", "seconds"]
    writer = csv.DictWriter(buf, fieldnames=keys)
    writer.writeheader()
    for r in rows:
        writer.writerow({k: r.get(k, "") for k in keys})
    table = os.path.join(args.outdir, "reconstruction.csv")
    results.write_text_atomic(table, buf.getvalue())
    from meshladar.viz import studies as vstudies

    (png,) = vstudies.draw_reconstruction(images, args.outdir)
    print(f"reconstruction study ({args.setting})")
    print("\n".join(study.report(rows)))
    print(f"  wrote {path}\n  wrote {table}\n  wrote {png}")
    return 0


def _cmd_bench(args) -> int:
    """Time the forward models and FBP against their peers (median of several runs)."""
    from .bench import report

    for line in report(repeats=args.repeats, full=args.full):
        print(line, flush=True)
    return 0


def _number(parse, ok, what):
    """An argparse type: ``parse(text)`` accepted when ``ok(value)``, else one message
    naming what is valid."""
    def convert(text: str):
        try:
            value = parse(text)
        except ValueError:
            value = None
        if value is None or not ok(value):
            raise argparse.ArgumentTypeError(f"must be a {what}; got {text!r}")
        return value

    convert.__name__ = what
    return convert


_positive_int = _number(int, lambda v: v >= 1, "positive integer")
_nonnegative_int = _number(int, lambda v: v >= 0, "non-negative integer")
_positive_float = _number(float, lambda v: v > 0 and math.isfinite(v),
                          "positive finite number")
_finite_float = _number(float, math.isfinite, "finite number")
_unit_fraction = _number(float, lambda v: 0 < v <= 1, "number in (0, 1]")
_nonnegative_float = _number(float, lambda v: v >= 0 and math.isfinite(v),
                             "non-negative finite number")


def _pair(text: str):
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != 2 or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"must be two finite numbers U,V; got {text!r}")
    return values



def _direction(text: str):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values) or \
            not any(values):
        raise argparse.ArgumentTypeError(f"must be a direction X,Y,Z (three finite numbers, "
                                         f"not all zero); got {text!r}")
    return values


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
               "  meshladar paper paper-figures/\n"
               "  meshladar simulate disk_pair -o pair.npz --coating small=aluminum\n"
               "  meshladar reconstruct pair.npz -o pair.png\n"
               "  meshladar view disk_pair --view-angle 0 --screenshot view.png\n"
               "  meshladar study faceting study/\n  meshladar bench",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    from . import __version__

    p.add_argument("--version", action="version", version=f"meshladar {__version__}")
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
    def scene_args(q):
        q.add_argument("scene", help="a packaged phantom's name (disk, ellipse, disk_pair), a "
                                     "phantom spec (.toml) or any mesh file trimesh reads "
                                     "(STL, OBJ, PLY, OFF, GLB/GLTF, 3MF, DAE, zip...)")
        q.add_argument("--material", default=None,
                       help="coating of a mesh's parts (default: dark_gray); a phantom's "
                            "shapes take --coating")
        q.add_argument("--coating", type=_coatings, default=None, metavar="PART=NAME,...",
                       help="coating per phantom shape or mesh part, e.g. small=aluminum "
                            "(default: each shape's own, or --material)")
        q.add_argument("--materials", default=None, metavar="TABLE.toml",
                       help="your own coating table: its names can be used by --material "
                            "and --coating (default: only the packaged coatings)")
        q.add_argument("--quiet", action="store_true",
                       help="no progress bar or summary (default: shown)")

    sim = sub.add_parser("simulate", help="simulate range profiles and save them",
                         description=_cmd_simulate.__doc__,
                         epilog="examples:\n  meshladar simulate disk_pair -o pair.npz "
                                "--coating small=aluminum\n"
                                "  meshladar simulate part.stl --material aluminum "
                                "--views 90 -o part.npz\n"
                                "  meshladar simulate part.stl --view-vectors 200 "
                                "--normals smooth -o part3d.npz\n"
                                "  meshladar simulate part.stl --mode slice --z0 0.1 "
                                "-o slice.npz\n"
                                "  meshladar simulate disk_pair --model mesh --tol 1e-2 "
                                "-o mesh.npz\n\n"
                                "Range r = -p.w is zero on the plane through the origin "
                                "facing the ladar and grows away from it. A mesh is a 3-D "
                                "target: the whole of it returns (values are areas x 1/sr); "
                                "--mode slice gives one slice per unit height.",
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    scene_args(sim)
    sim.add_argument("-o", "--output", required=True, help="result file (.npz)")
    sim.add_argument("--model", choices=MODELS, default=None,
                     help="forward model (default: analytic for phantoms, mesh for meshes)")
    sim.add_argument("--radiometry", choices=RADIOMETRIES, default=None,
                     help="paper: the paper's Eq. 8, ∫ F cos θ dA per bin (default); power: "
                          "the power a receiver collects, ∫ F cos θi cos θr dA (every model)")
    sens = sim.add_argument_group(
        "sensor (mesh model; SI units: metres, seconds, joules)",
        "a ladar at a finite standoff (perspective rays, ranges R - D from the origin), its "
        "beam, the "
        "atmosphere and the link budget: with --pulse-energy, --aperture and --standoff, "
        "received power (--radiometry power) is counted in photoelectrons per bin")
    sens.add_argument("--standoff", type=_positive_float, default=None, metavar="M",
                      help="distance D from the sensor to the origin (default: at infinity)")
    sens.add_argument("--flood-radius", type=_positive_float, default=None, metavar="M",
                      help="a top-hat flood of this radius at the origin (default: unbounded)")
    sens.add_argument("--beam-waist", type=_positive_float, default=None, metavar="M",
                      help="a Gaussian beam of this 1/e² radius at the sensor (default: "
                           "a flood)")
    sens.add_argument("--beam-divergence", type=_nonnegative_float, default=None,
                      metavar="RAD", help="its far-field 1/e² half-angle (default: 0)")
    sens.add_argument("--beam-offset", type=_pair, default=None, metavar="U,V",
                      help="its pointing offset at the origin along the view's u, v (m) "
                           "(default: 0,0)")
    sens.add_argument("--pulse-energy", type=_positive_float, default=None, metavar="J",
                      help="transmitted energy per pulse (default: none, relative units)")
    sens.add_argument("--aperture", type=_positive_float, default=None, metavar="M",
                      help="receiver aperture diameter (default: none, relative units)")
    sens.add_argument("--extinction", type=_nonnegative_float, default=None, metavar="PER_M",
                      help="atmospheric extinction coefficient, two-way exp(-2 sigma R) "
                           "(default: 0)")
    sens.add_argument("--wavelength", type=_positive_float, default=None, metavar="M",
                      help="laser wavelength (default: 1.064e-6)")
    sens.add_argument("--optics-transmission", type=_unit_fraction, default=None,
                      help="receive optics' transmission (default: 1)")
    sens.add_argument("--quantum-efficiency", type=_unit_fraction, default=None,
                      help="detector quantum efficiency (default: 1)")
    sim.add_argument("--views", type=_positive_int, default=None,
                     help="number of views evenly over 360 degrees about z (default: the "
                          "phantom's, or 360)")
    sim.add_argument("--angles-deg", type=_angle_list, default=None,
                     help="view angles about z in degrees, comma-separated (default: "
                          "from --views)")
    sim.add_argument("--view-vectors", type=_positive_int, default=None, metavar="N",
                     help="N view directions spread evenly over the sphere (mesh model) "
                          "(default: views about z)")
    sim.add_argument("--bins", type=_positive_int, default=None,
                     help="number of range bins (default: the phantom's, or 512 covering "
                          "the ranges the target spans over the views)")
    sim.add_argument("--bin-width", type=_positive_float, default=None,
                     help="range bin width in scene units (default: from --bins)")
    sim.add_argument("--segments", type=_positive_int, default=None,
                     help="tessellation of an analytic phantom for --model mesh (default: "
                          "1024)")
    sim.add_argument("--mode", choices=MODES, default=None,
                     help="mesh model: 3d (the whole target) or slice (one plane z = z0, "
                          "per unit height) (default: 3d for meshes, slice for phantoms)")
    sim.add_argument("--z0", type=_finite_float, default=None,
                     help="height of the slice plane for --mode slice (default: the "
                          "target's mid-height)")
    sim.add_argument("--normals", choices=NORMALS, default=None,
                     help="mesh model shading normals (default: flat; with --tol smooth "
                          "for meshes, exact for phantoms)")
    sim.add_argument("--ray-spacing", type=_positive_float, default=None,
                     help="distance between rays in scene units (default: from "
                          "--rays-per-bin)")
    sim.add_argument("--rays-per-bin", type=_positive_float, default=None,
                     help="rays per range-bin width (default: 1 in 3d, at least 128 across "
                          "the target; 8 in slice)")
    sim.add_argument("--backend", choices=BACKENDS, default=None,
                     help="mesh model ray casting: packets (coherent packets, Embree 4 from "
                          "the embreex wheel), embreex (one ray at a time, the reference) or "
                          "auto (default: packets when they load)")
    sim.add_argument("--sampling", choices=SAMPLINGS, default=None,
                     help="rays at a seeded random offset in their cell (stratified: "
                          "unbiased) or at cell centres (default: stratified in 3d, regular "
                          "in slice)")
    sim.add_argument("--seed", type=_nonnegative_int, default=None,
                     help="seed of the stratified sampling (default: 0)")
    sim.add_argument("--receiver", type=_direction, default=None, metavar="X,Y,Z",
                     help="bistatic receiver direction from the scene (default: collocated "
                          "with the ladar)")
    sim.add_argument("--footprint", action="store_true",
                     help="spread each ray over the range its footprint covers on the facet "
                          "(default: point binning)")
    sim.add_argument("--tol", type=_positive_float, default=None,
                     help="relative sinogram accuracy: meshladar picks rays and segments "
                          "(default: off)")
    sim.add_argument("--max-rays", type=_positive_float, default=None,
                     help="budget of rays for --tol over all its refinement runs (default: "
                          "2e9)")
    sim.add_argument("--pixel-size", type=_positive_float, default=None,
                     help="pixel size for --model pixel (default: a quarter bin)")
    sim.add_argument("--jobs", type=_positive_int, default=None,
                     help="worker processes, any model (default: 1; the mesh model uses "
                          "all cores from 4e6 rays)")
    sim.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="run on an existing Dask cluster (tcp://host:8786) "
                          "(default: local)")
    sim.add_argument("--workers", type=_positive_int, default=None,
                     help="run on a local Dask cluster of N processes "
                          "(default: no Dask)")
    sim.add_argument("--run-dir", default=None,
                     help="resumable run folder (any model): finished chunks are kept "
                          "there, and re-running the same command resumes (default: none)")
    sim.set_defaults(func=_cmd_simulate)

    rec = sub.add_parser("reconstruct", help="FBP of a saved sinogram into a PNG",
                         description=_cmd_reconstruct.__doc__,
                         epilog="examples:\n  meshladar reconstruct pair.npz -o pair.png\n"
                                "  meshladar reconstruct pair.npz -o pair-log.png --log",
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    rec.add_argument("result", help="a result file written by meshladar simulate")
    rec.add_argument("-o", "--output", required=True,
                     help="figure file: .png, .pdf, .svg, .jpg or .tif (the image's values go "
                          "to OUTPUT.image.npz beside it)")
    rec.add_argument("--size", type=_positive_int, default=None,
                     help="image size in pixels, or voxels per side for 3-D views (default: "
                          "512, 128 in 3-D)")
    rec.add_argument("--smooth", type=_nonnegative_float, default=None, metavar="BINS",
                     help="3-D views: Gaussian smoothing of each profile before the inversion "
                          "(default: 0)")
    rec.add_argument("--extent", type=_positive_float, default=None,
                     help="half-width of the image (default: the bins' reach)")
    rec.add_argument("--filter", choices=FILTERS, default=None,
                     help="FBP filter (default: ramp)")
    rec.add_argument("--log", action="store_true",
                     help="log of the radiance (Fig. 11a) (default: off)")
    rec.add_argument("--clip", type=_unit_fraction, default=None,
                     help="clip at this fraction of the maximum (Fig. 11b: 0.008) (default: "
                          "off)")
    rec.add_argument("--quiet", action="store_true", help="no summary line (default: shown)")
    rec.set_defaults(func=_cmd_reconstruct)

    rc = sub.add_parser("receive", help="waveforms (and noise) from a saved sinogram",
                        description=_cmd_receive.__doc__,
                        epilog="examples:\n  meshladar simulate part.stl -o part.npz --model "
                               "mesh --radiometry power --standoff 1000 --beam-waist 0.05 "
                               "--beam-divergence 1e-4 --pulse-energy 1e-3 --aperture 0.1\n"
                               "  meshladar receive part.npz -o part-waves.npz --sample-rate "
                               "2e9 --pulse-fwhm 1e-9 --realisations 100 --speckle-cells 1 "
                               "--seed 0 --plot part-waves.png",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    rc.add_argument("result", help="a sinogram written by meshladar simulate")
    rc.add_argument("-o", "--output", required=True, help="waveforms file (.npz)")
    rc.add_argument("--sample-rate", type=_positive_float, required=True, metavar="HZ",
                    help="digitiser rate, samples per second")
    rc.add_argument("--pulse-fwhm", type=_positive_float, default=None, metavar="S",
                    help="Gaussian transmitted pulse, full width at half maximum (default: "
                         "a Dirac pulse)")
    rc.add_argument("--pulse-samples", default=None, metavar="FILE",
                    help="the pulse's own shape: a text file of power samples (commas, spaces "
                         "or newlines), with --pulse-interval (default: none)")
    rc.add_argument("--pulse-interval", type=_positive_float, default=None, metavar="S",
                    help="seconds between --pulse-samples (default: none)")
    rc.add_argument("--response-fwhm", type=_positive_float, default=None, metavar="S",
                    help="Gaussian receiver impulse response (default: ideal)")
    rc.add_argument("--standoff", type=_nonnegative_float, default=None, metavar="M",
                    help="time origin t = 2(r + D)/c (default: the simulation's sensor's, "
                         "else 0)")
    rc.add_argument("--oversample", type=_positive_int, default=8,
                    help="fine cells per sample for the convolutions (default: %(default)s)")
    rc.add_argument("--scale", type=_positive_float, default=None, metavar="PE_PER_UNIT",
                    help="photoelectrons per unit of the sinogram, when it was not simulated "
                         "with --pulse-energy and --aperture (default: none)")
    rc.add_argument("--realisations", type=_positive_int, default=None, metavar="N",
                    help="draw N noise realisations (default: none)")
    rc.add_argument("--seed", type=_nonnegative_int, default=None,
                    help="seed of the noise (default: fresh entropy)")
    rc.add_argument("--speckle-cells", type=_positive_float, default=None, metavar="M",
                    help="speckle cells per resolution cell, >= 1 (default: no speckle)")
    rc.add_argument("--background-rate", type=_nonnegative_float, default=None,
                    metavar="PER_S", help="background photoelectrons per second (default: 0)")
    rc.add_argument("--dark-rate", type=_nonnegative_float, default=None, metavar="PER_S",
                    help="dark counts per second (default: 0)")
    rc.add_argument("--excess-noise", type=_positive_float, default=None, metavar="F",
                    help="APD excess noise factor, >= 1 (default: 1)")
    rc.add_argument("--gain", type=_positive_float, default=None,
                    help="APD mean gain (default: 1)")
    rc.add_argument("--bits", type=_positive_int, default=None,
                    help="digitiser bits, with --full-scale (default: no quantisation)")
    rc.add_argument("--full-scale", type=_positive_float, default=None,
                    help="digitiser full scale in output units, with --bits (default: "
                         "none)")
    rc.add_argument("--plot", default=None, metavar="PNG",
                    help="a figure of a few views' waveforms with their noise band "
                         "(default: none)")
    rc.add_argument("--quiet", action="store_true", help="no summary line (default: shown)")
    rc.set_defaults(func=_cmd_receive)

    vw = sub.add_parser("view", help="3-D view of a scene coloured by its return",
                        description=_cmd_view.__doc__,
                        epilog="examples:\n  meshladar view disk_pair --view-angle 0 "
                               "--screenshot pair.png\n  meshladar view part.glb "
                               "--material aluminum",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    scene_args(vw)
    vw.add_argument("--view-angle", type=_finite_float, default=90.0,
                    help="view angle about z in degrees (default: %(default)s)")
    vw.add_argument("--screenshot", default=None,
                    help="render off screen into this PNG (default: open a window)")
    vw.add_argument("--log", action="store_true",
                    help="colour by log10 of the return (default: linear)")
    vw.add_argument("--size", type=_window_size, default=(900, 700), metavar="WxH",
                    help="window or screenshot size in pixels (default: 900x700)")
    vw.add_argument("--camera", choices=("oblique", "view"), default="oblique",
                    help="oblique: beside and above the ladar; view: along the beam from "
                         "the ladar (default: %(default)s)")
    vw.set_defaults(func=_cmd_view)

    st = sub.add_parser("study", help="faceting-vs-analytic study into a folder",
                        description=_cmd_study.__doc__,
                        epilog="examples:\n  meshladar study faceting study/\n"
                               "  meshladar study faceting study-full/ --full",
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    st.add_argument("kind", choices=["faceting", "tomography3d", "reconstruction"],
                    help="which study: faceting (forward models against the analytic one), "
                         "tomography3d (the paper's findings in 3-D) or reconstruction "
                         "(FBP and iterative methods against view spacing)")
    st.add_argument("outdir", help="folder for faceting.csv/json, results and figures")
    st.add_argument("--full", dest="setting", action="store_const", const="full",
                    default="quick", help="the full sweep (faceting: 360 views, segments to "
                                          "4096; tomography3d: 2000 views, 128^3) (default: "
                                          "the quick one)")
    st.add_argument("--photons", type=_positive_float, default=None,
                    help="reconstruction study: photon-counting noise with this many "
                         "photoelectrons in each sinogram's brightest bin (default: none)")
    st.add_argument("--speckle", type=_positive_float, default=None, metavar="M",
                    help="reconstruction study, with --photons: speckle of M >= 1 cells per "
                         "bin (1: fully developed) (default: none)")
    st.add_argument("--background", type=_positive_float, default=None, metavar="B",
                    help="reconstruction study, with --photons: B background "
                         "photoelectrons per bin, its mean subtracted (default: none)")
    st.add_argument("--quiet", action="store_true", help="no progress bar (default: shown)")
    st.epilog += ("\n\nFinished study points are kept in OUTDIR/run: re-running the same "
                  "command resumes an interrupted study.")
    st.set_defaults(func=_cmd_study)
    bch = sub.add_parser("bench", help="time the forward models (median of several runs)",
                         description=_cmd_bench.__doc__,
                         epilog="example:\n  meshladar bench --repeats 7",
                         formatter_class=argparse.RawDescriptionHelpFormatter)
    bch.add_argument("--repeats", type=_positive_int, default=5,
                     help="timed runs per case after one warm-up (default: %(default)s)")
    bch.add_argument("--full", action="store_true",
                     help="also the streaming run: 360 views x 1e6 rays (about a minute) "
                          "(default: off)")
    bch.set_defaults(func=_cmd_bench)
    return p


def _one_line_warning(message, category, filename, lineno, line=None):
    return f"meshladar: warning: {message}\n"


def main(argv=None) -> int:
    """Run the command line; returns the exit status."""
    import warnings

    parser = _parser()
    args = parser.parse_args(argv)
    previous = _terminate_as_interrupt()
    format_before, warnings.formatwarning = warnings.formatwarning, _one_line_warning
    try:
        return args.func(args)
    except MeshladarError as exc:
        print(f"meshladar: error: {exc}", file=sys.stderr)
        return 2
    except ImportError as exc:       # an optional extra that is not installed: named there
        print(f"meshladar: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        where = f" {exc.filename!r}" if getattr(exc, "filename", None) else ""
        print(f"meshladar: error:{where} {exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        hint = ""
        if getattr(args, "run_dir", None):
            hint = (f"; finished chunks are kept in {args.run_dir}: run the same command "
                    "again to resume")
        print(f"meshladar: interrupted{hint}", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - a bug of meshladar's own: say so in one line
        path = _save_traceback()
        print(f"meshladar: internal error ({type(exc).__name__}: "
              f"{' '.join(str(exc).split())[:200]}); this is a bug in meshladar, please "
              f"report it with the traceback in {path}", file=sys.stderr)
        return 1
    finally:
        warnings.formatwarning = format_before           # a caller's own is left as it was
        if previous is not None:
            import signal

            signal.signal(signal.SIGTERM, previous)


def _save_traceback():
    """Write the current exception's traceback to a new file; return its path."""
    import tempfile
    import traceback

    fd, path = tempfile.mkstemp(prefix="meshladar-traceback-", suffix=".txt")
    with open(fd, "w", encoding="utf-8") as fh:
        traceback.print_exc(file=fh)
    return path


def _terminate_as_interrupt():
    """SIGTERM stops a run as Ctrl-C does (workers cancelled, finished chunks kept, a
    resume hint); returns the previous handler, or None off the main thread."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    return signal.signal(signal.SIGTERM, interrupt)
