"""``meshladar reconstruct`` (FBP or the 3-D inversion of a saved sinogram) and
``meshladar receive`` (waveforms and noise from a saved sinogram)."""

from __future__ import annotations

import os
import re
import warnings

from .. import io, plotting
from ..errors import MeshladarWarning, ParameterError
from ..noise import Noise
from ..sensor import LIMITS as SENSOR_LIMITS
from ..waveforms import MAX_OVERSAMPLE, SAMPLE_RATE_RANGE, GaussianPulse, SampledPulse, receive
from .._validate import check_count, check_real
from ..reconstruct import clip_radiance, fbp, log_radiance
from ..reconstruct.volumes import fbp3d
from .checks import check_not_input, check_output
from .words import flag_words

__all__ = ["cmd_reconstruct", "cmd_receive", "IMAGE_SUFFIXES", "VALUES_SUFFIX",
           "reconstruct_words", "receive_words"]

#: Image formats reconstruct writes (matplotlib's own writers; JPEG and TIFF through Pillow,
#: a dependency of matplotlib).
IMAGE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".tif", ".tiff")
#: reconstruct's -o with this extension writes the values alone, no figure (no matplotlib).
VALUES_SUFFIX = ".npz"


def _save_figure(fig, output):
    """``fig`` to ``output`` (by its extension); nothing for a values-only ``.npz``."""
    if output.lower().endswith(VALUES_SUFFIX):
        return
    fmt = os.path.splitext(output)[1].lower().lstrip(".")
    io.write_atomic(output, lambda fh: fig().savefig(fh, format=fmt, dpi=150))


def cmd_reconstruct(args) -> int:
    """Reconstruct a saved sinogram by FBP: a figure (PNG, PDF, SVG, JPEG or TIFF, chosen by
    the extension of -o) and the image's values in OUTPUT.image.npz; or, where -o ends in
    ``.npz``, the values alone in it (no figure: matplotlib is not needed).

    A sinogram whose views are not all about z (``--view-vectors``) is inverted in 3-D
    instead (:func:`meshladar.reconstruct.volumes.fbp3d`): the figure shows three slices
    through the target and the volume goes to OUTPUT.volume.npz. ``--log`` and then
    ``--clip`` preprocess the sinogram first.

    Parameters
    ----------
    args : argparse.Namespace
        ``result``: the ``.npz`` written by ``meshladar simulate``; ``output``: the figure's
        path (its extension one of :data:`IMAGE_SUFFIXES`), or the values' (``.npz``,
        :data:`VALUES_SUFFIX`); ``size``: pixels per side
        (default 512), or voxels per side in 3-D (default 128); ``extent``: the half-width
        of the image or cube in scene units (default None: the bins' reach);
        ``filter``: the FBP filter (default ``"ramp"``; 2-D only); ``smooth``: Gaussian
        smoothing of each profile in bins (3-D only; default 0); ``log``: reconstruct the
        log of the radiance; ``clip``: clip at this fraction of the maximum, in (0, 1];
        ``quiet``: no summary line.

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    ParameterError
        Before the work: when ``output`` has an extension not in :data:`IMAGE_SUFFIXES`
        or ``.npz``, cannot be written where it is, or it or the data file beside it
        (``OUTPUT.image.npz``, or ``OUTPUT.volume.npz`` in 3-D) would overwrite ``result``
        or is a folder; when ``smooth`` is given for views about z, or ``filter`` for 3-D
        views; and the API's own refusals (an unreadable result, an image too large).
    ImportError
        When a figure is asked for and matplotlib is not installed (before the work).
    """
    check_output(args.output, IMAGE_SUFFIXES + (VALUES_SUFFIX,), [args.result])
    values_only = args.output.lower().endswith(VALUES_SUFFIX)
    if not values_only:
        plotting.require("matplotlib")          # before the work, not after it
    sino, meta = io.load_sinogram(args.result)
    data = args.output if values_only else (os.path.splitext(args.output)[0]
                                            + (".image.npz" if sino.planar else ".volume.npz"))
    if not values_only:
        check_not_input(args.output, data, args.result,
                        "image data" if sino.planar else "volume")
    if args.log:
        sino = log_radiance(sino)
    if args.clip is not None:
        sino = clip_radiance(sino, threshold=args.clip)
    # no --extent: the API's default (the bins' reach about the origin), the same grid as
    # meshladar.fbp(sino) and meshladar.reconstruct.volumes.fbp3d(sino)
    if not sino.planar:
        if args.center is not None:
            raise ParameterError("--center places the image of views about the z axis; 3-D "
                                 "views are inverted on a cube about the origin (leave out "
                                 "--center)")
        return _reconstruct_3d(args, sino, args.extent, data)
    if args.smooth is not None:
        raise ParameterError("--smooth applies to 3-D views (fbp3d); this sinogram's views "
                             "are about the z axis (use --filter)")
    image = fbp(sino, size=args.size or 512, extent=args.extent, filter=args.filter or "ramp",
                center=args.center or (0.0, 0.0))
    extent = image.extent
    # the quick look's symmetric scale, log input labelled as such, and a centre slice
    prep = sino.info.get("preprocess")
    _save_figure(lambda: plotting.viz("quick").image(
        image, title=f"FBP of {os.path.basename(args.result)}" + (f", {prep}" if prep else "")
        + f" ({args.filter or 'ramp'} filter)"), args.output)
    io.save_result(data, {"image": image.values},
                        {"kind": "image", "extent": extent, "info": image.info,
                         "source": os.path.basename(args.result)})
    if not args.quiet:
        size = args.size or 512
        print(f"wrote {_written(args.output, data)} ({size}x{size}, extent {extent:g})")
    return 0


def _written(output, data):
    """The files a reconstruction wrote, for its summary line."""
    return data if output == data else f"{output} and {data}"


def _reconstruct_3d(args, sino, extent, data) -> int:
    """reconstruct for views over the sphere: the 3-D Radon inversion
    (meshladar.reconstruct.volumes.fbp3d), three slices through the target as the figure,
    the volume in ``data`` (OUTPUT.volume.npz, checked by the caller)."""
    if args.filter is not None:
        raise ParameterError("--filter applies to FBP of views about the z axis; 3-D views "
                             "are inverted with a second difference (use --smooth BINS)")
    size = args.size or 128
    vol = fbp3d(sino, size=size, extent=extent, smooth=args.smooth or 0.0)
    extent = vol.info["extent"]
    _save_figure(lambda: plotting.viz("quick").volume(
        vol, title=f"3-D Radon inversion of {os.path.basename(args.result)} "
                   f"({sino.n_views} views, {size}^3)"), args.output)
    io.save_result(data, {"values": vol.values, "x": vol.x, "y": vol.y, "z": vol.z},
                        {"kind": "volume", "info": vol.info,
                         "source": os.path.basename(args.result)})
    if not args.quiet:
        print(f"wrote {_written(args.output, data)} ({size}^3, extent {extent:g}, "
              f"{sino.n_views} views)")
    return 0


def read_samples(path):
    """A pulse's samples from a text file: numbers separated by commas, spaces or newlines
    (# starts a comment).

    Parameters
    ----------
    path : str
        The ``--pulse-samples`` file.

    Returns
    -------
    list of float
        The samples, in the file's order.

    Raises
    ------
    ParameterError
        Naming ``--pulse-samples`` and the file: when it cannot be read (missing, a
        folder, no permission) or is not text of numbers.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            text = " ".join(line.split("#")[0] for line in fh)
        values = [float(x) for x in text.replace(",", " ").split()]
    except UnicodeDecodeError:
        raise ParameterError(f"--pulse-samples {path!r}: not a text file of numbers") from None
    except ValueError as exc:
        raise ParameterError(f"--pulse-samples {path!r}: {exc}") from None
    except OSError as exc:
        raise ParameterError(f"--pulse-samples {path!r}: cannot be read "
                             f"({(exc.strerror or str(exc)).lower()})") from None
    return values


#: receive's noise flags (argparse attribute → Noise field); --seed shapes the draws too.
_NOISE_FIELDS = {"speckle_cells": "speckle_cells", "background_rate": "background_rate",
                 "dark_rate": "dark_rate", "excess_noise": "excess_noise_factor",
                 "gain": "gain", "bits": "bits", "full_scale": "full_scale"}


#: The translator of the API's messages into reconstruct's flags
#: (:func:`.words.flag_words`): ``reconstruct_words(message)`` names each option
#: reconstruct sets by its flag, and gives the bins' advice in simulate's flags.
_words = flag_words(
    {"size": "--size", "extent": "--extent", "smooth": "--smooth", "filter": "--filter",
     "threshold": "--clip"},
    phrases=[("wider bins (meshladar.reconstruct.resample_uniform) or more views",
              "fewer, wider bins or more views (simulate --bins, --views)")])


def reconstruct_words(message):
    """An API message in reconstruct's flags (:data:`_words`), the image's centre
    ``center=(X, Y)`` as ``--center X,Y``.

    Parameters
    ----------
    message : str
        The API's message.

    Returns
    -------
    str
        The message in the command's flags.
    """
    return re.sub(r"\bcenter=\(([^,()]+), ([^,()]+)\)", r"--center \1,\2", _words(message))
#: The translator of the API's messages into receive's flags (:func:`.words.flag_words`):
#: ``receive_words(message)`` names the waveforms' and the noise's parameters by their
#: flags (a pulse's and the response's ``fwhm`` are named where they are made).
receive_words = flag_words(
    {"sample_rate": "--sample-rate", "oversample": "--oversample", "standoff": "--standoff",
     "scale": "--scale", "seed": "--seed", "interval": "--pulse-interval",
     **{field: "--" + a.replace("_", "-") for a, field in _NOISE_FIELDS.items()}},
    ("sample_rate", "oversample", "standoff", "speckle_cells", "background_rate",
     "dark_rate", "excess_noise_factor", "full_scale", "bits"))


def _gaussian(flag, fwhm):
    """A Gaussian pulse of ``fwhm`` seconds, refused in ``flag``'s words."""
    try:
        return GaussianPulse(fwhm)
    except ParameterError as exc:
        raise ParameterError(str(exc).replace("fwhm", flag, 1)) from None


def _check_receiver(args):
    """receive's numbers refused in its flags' words before the sinogram is read: the
    digitiser's rate, the oversampling, the standoff (as :func:`meshladar.waveforms.receive`
    checks them), the response and the noise (as they are made)."""
    check_real("--sample-rate", args.sample_rate, low=SAMPLE_RATE_RANGE[0],
               high=SAMPLE_RATE_RANGE[1])
    check_count("--oversample", args.oversample, high=MAX_OVERSAMPLE)
    if args.standoff is not None:
        check_real("--standoff", args.standoff, low=0.0, high=SENSOR_LIMITS["standoff"])
    response = None if args.response_fwhm is None else _gaussian("--response-fwhm",
                                                                 args.response_fwhm)
    return response, _noise_model(args)


def _pulse(args):
    if args.pulse_fwhm is not None and args.pulse_samples is not None:
        raise ParameterError("--pulse-fwhm and --pulse-samples both give the pulse; give one")
    if (args.pulse_samples is None) != (args.pulse_interval is None):
        raise ParameterError("--pulse-samples needs --pulse-interval (s between samples), "
                             "and the other way round")
    if args.pulse_samples is not None:
        return SampledPulse(read_samples(args.pulse_samples), args.pulse_interval)
    return None if args.pulse_fwhm is None else _gaussian("--pulse-fwhm", args.pulse_fwhm)


def _check_noise_flags(args):
    """The noise flags (and --seed) need --realisations: refused without it, before the
    work."""
    given = [a for a in (*_NOISE_FIELDS, "seed") if getattr(args, a) is not None]
    if args.realisations is None and given:
        raise ParameterError(f"--{given[0].replace('_', '-')} shapes the noise: give "
                             "--realisations N too")


def _noise_model(args):
    """The noise the flags give, None without --realisations."""
    if args.realisations is None:
        return None
    return Noise(**{field: getattr(args, a) for a, field in _NOISE_FIELDS.items()
                    if getattr(args, a) is not None})


def _load_for_receiver(args):
    """The saved sinogram, refused when ``--scale`` is given for one that already counts
    photoelectrons, with a warning (unless quiet) when it is not a receiver's power."""
    sino, _ = io.load_sinogram(args.result)
    if args.scale is not None and sino.units == "photoelectrons":
        raise ParameterError(f"--scale converts relative power to photoelectrons; "
                             f"{args.result} already counts photoelectrons (simulated with "
                             "--pulse-energy and --aperture): drop --scale")
    if sino.radiometry != "power" and not args.quiet:
        warnings.warn(f"{args.result} holds {sino.radiometry or 'paper'!r} "
                      "radiometry (Eq. 8), not the power a receiver collects: simulate with "
                      "--radiometry power for a receiver's waveform", MeshladarWarning)
    return sino


def cmd_receive(args) -> int:
    """Turn a saved sinogram's range bins into digitised waveforms (two-way time, the
    transmitted pulse, the receiver's impulse response, the digitiser's rate), optionally
    with noise realisations (photon counting, speckle, background and dark counts, APD
    gain and excess noise, quantisation); save them, and a figure with --plot.

    The waveforms (:func:`meshladar.waveforms.receive`) and any noise realisations are
    saved with :func:`meshladar.io.save_waveforms`; the figure is
    :func:`meshladar.viz.waveforms.draw`. A sinogram not simulated with
    ``--radiometry power`` warns (a :class:`~meshladar.errors.MeshladarWarning`) unless
    ``--quiet``.

    Parameters
    ----------
    args : argparse.Namespace
        ``result``: the ``.npz`` written by ``meshladar simulate``; ``output``: the
        waveforms' ``.npz`` path; ``sample_rate``: the digitiser's rate in samples per
        second; ``oversample``: fine cells per sample for the convolutions (int);
        ``pulse_fwhm`` (s, a Gaussian pulse) or ``pulse_samples`` (a text file of power
        samples) with ``pulse_interval`` (s between them), None for a Dirac pulse;
        ``response_fwhm``: the receiver's Gaussian impulse response in s (None: ideal);
        ``standoff``: D in metres, the time origin t = 2(r + D)/c (None: the
        simulation's sensor's, else 0); ``scale``: photoelectrons per unit of the
        sinogram; ``realisations``: the number of noise draws (None: no noise) and their
        ``seed``; the noise options ``speckle_cells``, ``background_rate`` and
        ``dark_rate`` (per s), ``excess_noise``, ``gain``, ``bits`` and ``full_scale``
        (:class:`meshladar.noise.Noise`'s fields); ``plot``: a ``.png`` path for the
        figure, or None; ``quiet``: no warning or summary line.

    Returns
    -------
    int
        0, the exit status.

    Raises
    ------
    ParameterError
        Before the work: when ``output`` is not a ``.npz`` path, is ``result`` or cannot
        be written where it is; when ``plot`` is not a ``.png`` path or names ``result`` or
        ``output``; when ``scale`` is given for a
        sinogram that already counts photoelectrons; when both ``pulse_fwhm`` and
        ``pulse_samples`` are given, or one of ``pulse_samples`` and ``pulse_interval``
        without the other, or the samples file is not text of numbers; when a noise
        option or ``seed`` is given without ``realisations``; and the API's own refusals.
    ImportError
        With ``plot``, when matplotlib is not installed (checked before the work).
    """
    check_output(args.output, (".npz",), [args.result])
    if args.plot is not None:
        check_output(args.plot, (".png",), [args.result], "--plot",
                     others=[("-o", args.output)])
        plotting.require("matplotlib")          # before the work, not after it
    _check_noise_flags(args)
    pulse = _pulse(args)                        # reads --pulse-samples: before the work
    response, noise = _check_receiver(args)
    sino = _load_for_receiver(args)
    waves = receive(sino, sample_rate=args.sample_rate, pulse=pulse, response=response,
                    standoff=args.standoff, oversample=args.oversample)
    if args.scale is not None:
        waves = waves.scaled(args.scale)
    draws = None if noise is None else waves.realise(noise, args.realisations,
                                                     seed=args.seed)
    params = {"source": os.path.basename(args.result), "seed": args.seed,
              "realisations": args.realisations}
    io.save_waveforms(args.output, waves, realisations=draws, noise=noise,
                           params=params)
    if args.plot is not None:
        plotting.viz("waveforms").draw(waves, args.plot, realisations=draws, noise=noise)
    if not args.quiet:
        extra = "" if draws is None else f", {len(draws)} noise realisations"
        print(f"{args.result}: {waves.values.shape[0]} views x {waves.values.shape[1]} "
              f"samples at {args.sample_rate:g} Hz over two-way time "
              f"[{waves.time_edges[0]:.6g}, {waves.time_edges[-1]:.6g}] s, units "
              f"{waves.units}{extra}; wrote {args.output}"
              + ("" if args.plot is None else f" and {args.plot}"))
    return 0
