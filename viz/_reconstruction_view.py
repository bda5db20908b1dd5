"""The viewer's reconstructions (see :mod:`meshladar.viz.viewer`, which re-exports these
entry points): a reconstructed slice placed in 3-D (:func:`show_slice`), and a stack of
slices or a :class:`meshladar.images.Volume` as an iso-surface or a volume rendering
(:func:`show_volume`, :func:`volume_surface`, :func:`volume_iso`).
"""

from __future__ import annotations

import numpy as np

from meshladar._validate import check_choice, check_real, finite_array, short
from meshladar.errors import ParameterError
from meshladar.images import Image, Volume

from ._frame import (_bar, _clear_of_bars, _corners, _finish, _headless_window, _legend,
                     _mesh_scene, _pyvista)

__all__ = ["show_slice", "show_volume", "volume_surface", "volume_iso"]


def _image_data(pv, image, z):
    img = np.asarray(image.values)
    grid = pv.ImageData(dimensions=(img.shape[1] + 1, img.shape[0] + 1, 1),
                        spacing=(image.pixel_size, image.pixel_size, 1.0),
                        origin=(image.x[0] - image.pixel_size / 2,
                                image.y[0] - image.pixel_size / 2, z))
    grid.cell_data["reconstruction"] = img.ravel(order="C")
    return grid


@_headless_window
def show_slice(image, *, z=0.0, scene=None, clim=None, off_screen=False, screenshot=None,
               window_size=(800, 700), camera=None):
    """A reconstructed slice (an ``Image``) placed in 3-D at height ``z``, optionally with
    the scene's mesh as a wireframe. Cell (i, j) of the slice sits at (x_j, y_i, z).

    Parameters
    ----------
    image : Image
        The slice; each pixel is drawn as a cell of its size, grey-scale, with a colour
        bar.
    z : float, keyword-only
        The slice's height, scene units (default 0.0).
    scene : Scene, optional, keyword-only
        Drawn as an orange wireframe (an analytic scene as prisms of 128 sides).
    clim : (low, high), optional, keyword-only
        The colour scale's limits (default None: pyvista's, the values' range).
    off_screen, screenshot, window_size : keyword-only
        See the module docstring; ``window_size`` (width, height) in pixels, default
        (800, 700).
    camera : pyvista camera position, optional, keyword-only
        Default None: above the slice's centre at 4 × its half-width, looking down, y up,
        the picture made smaller and moved just enough to clear the colour bar's slot
        and the legend (a camera given is kept as given).

    Returns
    -------
    Shown
        The image off screen, or the plotter on a desktop (module docstring).

    Raises
    ------
    ImportError
        When pyvista is not installed.
    """
    pv = _pyvista()
    plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
    plotter.set_background("black")
    grid = _image_data(pv, image, z)
    legend = None
    inp = image.info.get("preprocess") or ""
    plotter.add_mesh(grid, scalars="reconstruction", cmap="gray", lighting=False, clim=clim,
                     scalar_bar_args=_bar("reconstruction of log input" if
                                          inp.startswith("log") else
                                          "reconstruction [radiance / area]", 0))
    if scene is not None:
        mesh = _mesh_scene(scene, 128)
        for p in mesh.parts:
            cells = np.hstack([np.full((len(p.faces), 1), 3), p.faces]).ravel()
            plotter.add_mesh(pv.PolyData(p.vertices, cells), style="wireframe",
                             color="orange", opacity=0.3, lighting=False)
        legend = _legend(plotter, [("scene (wireframe)", (1.0, 0.65, 0.0))])
    c = (float(image.center[0]), float(image.center[1]), float(z))
    plotter.camera_position = camera if camera is not None else [
        (c[0], c[1], c[2] + 4.0 * image.extent), c, (0.0, 1.0, 0.0)]
    if camera is None:                    # the default view: clear of the bar and legend
        _clear_of_bars(plotter, _corners(plotter), grow=False, legend=legend)
    return _finish(plotter, off_screen, screenshot)


def volume_iso(volume):
    """A default iso-value for a reconstructed volume: half its 99.9th percentile (the
    bright surface shell, not the FBP side-lobes and noise around it).

    Parameters
    ----------
    volume : Volume
        The reconstruction.

    Returns
    -------
    float
        0.5 × the 99.9th percentile of all its (signed) values.
    """
    v = np.asarray(volume.values)
    return 0.5 * float(np.percentile(v, 99.9))


def volume_surface(volume, iso=None):
    """The iso-surface of a :class:`meshladar.images.Volume` at ``iso`` (default
    :func:`volume_iso`) as a pyvista mesh in scene coordinates.

    Parameters
    ----------
    volume : Volume
        The reconstruction; its values sit on the points of a grid through the voxel
        centres.
    iso : float, optional
        The iso-value (default None: :func:`volume_iso`).

    Returns
    -------
    pyvista.PolyData
        The surface (empty when no value crosses ``iso``).

    Raises
    ------
    ImportError
        When pyvista is not installed.
    """
    pv = _pyvista()
    dx, dy, dz = volume.spacing
    grid = pv.ImageData(dimensions=(volume.x.size, volume.y.size, volume.z.size),
                        spacing=(dx, dy, dz), origin=(volume.x[0], volume.y[0], volume.z[0]))
    grid.point_data["reconstruction"] = np.asarray(volume.values).ravel(order="C")
    return grid.contour([volume_iso(volume) if iso is None else iso],
                        scalars="reconstruction")


@_headless_window
def show_volume(images, zs=None, *, iso=None, render="iso", off_screen=False,
                screenshot=None, window_size=(800, 700), camera=None):
    """A stack of reconstructed slices at heights ``zs`` (increasing, evenly spaced), or a
    :class:`meshladar.images.Volume` (then ``zs`` is not given), as the iso-surface at value
    ``iso`` (default: for a Volume :func:`volume_iso`, for a stack half its 99.5th
    percentile, where the bright surfaces are), or with ``render="volume"`` (stacks) as a
    volume rendering with a robust window and a sigmoid opacity.

    Parameters
    ----------
    images : Volume or sequence of Image
        A Volume (always drawn as its iso-surface: ``render`` is checked but not used),
        or at least two images, one per height in ``zs``, all placed on the first one's
        grid (not checked); the stack's values sit on the points of a grid through the
        pixel centres.
    zs : (n,) array_like, optional
        The images' heights, scene units; not given with a Volume.
    iso : float, optional, keyword-only
        The iso-value. Default None: for a Volume :func:`volume_iso`; for a stack half the
        99.5th percentile of its positive values (0 when it has none).
    render : {"iso", "volume"}, keyword-only
        For a stack: the iso-surface (default), or a volume rendering (``magma``, colour
        limits 0 to the 99.5th percentile of the positive values, a colour bar).
    off_screen, screenshot, window_size : keyword-only
        See the module docstring; ``window_size`` (width, height) in pixels, default
        (800, 700).
    camera : pyvista camera position, optional, keyword-only
        Default None: pyvista's isometric view (a volume rendering's made smaller and
        moved just enough to clear its colour bar's slot; a camera given is kept).

    Returns
    -------
    Shown
        The image off screen, or the plotter on a desktop (module docstring).

    Raises
    ------
    ParameterError
        When ``render`` is neither choice, ``iso`` is not a finite number, ``images`` is
        neither a Volume nor a list or tuple of Images, ``zs`` is given with a Volume or
        missing with a stack, ``images`` and ``zs`` differ in length or have fewer than
        two, or ``zs`` is not finite, increasing and evenly spaced; all checked before
        pyvista is imported (a ParameterError is a ``ValueError``).
    ImportError
        When pyvista is not installed.
    """
    zs = _check_volume(images, zs, iso, render)
    pv = _pyvista()
    if isinstance(images, Volume):
        plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
        plotter.set_background("black")
        plotter.add_mesh(volume_surface(images, iso), color="white", smooth_shading=True)
        _aim(plotter, camera)
        return _finish(plotter, off_screen, screenshot)
    vol, grid = _stack(pv, images, zs)
    plotter = pv.Plotter(off_screen=off_screen, window_size=window_size)
    plotter.set_background("black")
    if render == "volume":
        # a robust window and a sigmoid opacity: the surfaces glow, the noise stays clear
        vals = vol[vol > 0]
        top = float(np.percentile(vals, 99.5)) if vals.size else 1.0
        plotter.add_volume(grid, scalars="reconstruction", cmap="magma", opacity="sigmoid",
                           clim=(0.0, top), scalar_bar_args=_bar("reconstruction", 0))
        _aim(plotter, camera)
        if camera is None:                # pyvista's isometric view, clear of the bar
            _clear_of_bars(plotter, _corners(plotter), grow=False)
        return _finish(plotter, off_screen, screenshot)
    if iso is None:                       # half the robust peak: the bright surfaces
        vals = vol[vol > 0]
        iso = 0.5 * float(np.percentile(vals, 99.5)) if vals.size else 0.0
    plotter.add_mesh(grid.contour([iso], scalars="reconstruction"), color="white",
                     smooth_shading=True)
    _aim(plotter, camera)
    return _finish(plotter, off_screen, screenshot)


def _check_volume(images, zs, iso, render):
    """show_volume's arguments, checked before any work: ``zs`` as a float64 array (None
    with a Volume)."""
    check_choice("render", render, ("iso", "volume"))
    if iso is not None:
        check_real("iso", iso)
    if isinstance(images, Volume):
        if zs is not None:
            raise ParameterError(f"a Volume carries its own z; do not give zs; got zs="
                                 f"{short(zs)}")
        return None
    if not isinstance(images, (list, tuple)) or not all(isinstance(im, Image)
                                                        for im in images):
        raise ParameterError(f"images must be a Volume or a list or tuple of Images; got "
                             f"{short(images)}")
    if zs is None:
        raise ParameterError("a stack of images needs zs, one height per image; got "
                             "zs=None")
    zs = finite_array("zs", zs)
    if zs.ndim != 1 or len(images) != zs.size or zs.size < 2:
        raise ParameterError(f"images and zs must have the same length >= 2; got "
                             f"{len(images)} images and zs of shape {zs.shape}")
    dz = np.diff(zs)
    if np.any(dz <= 0) or np.ptp(dz) > 1e-9 * dz.mean():
        raise ParameterError(f"zs must be increasing and evenly spaced; got {short(zs)}")
    return zs


def _stack(pv, images, zs):
    """A stack of slices at heights ``zs`` (checked by :func:`_check_volume`): its values
    (nz, ny, nx) and a pyvista grid of them on the points through the first image's pixel
    centres."""
    dz = np.diff(zs)
    first = images[0]
    vol = np.stack([np.asarray(im.values) for im in images])          # (nz, ny, nx)
    grid = pv.ImageData(dimensions=(vol.shape[2], vol.shape[1], vol.shape[0]),
                        spacing=(first.pixel_size, first.pixel_size, float(dz[0])),
                        origin=(first.x[0], first.y[0], zs[0]))
    grid.point_data["reconstruction"] = vol.ravel(order="C")
    return vol, grid


def _aim(plotter, camera):
    """Place the camera at ``camera``, or (None) at pyvista's isometric view."""
    if camera is not None:
        plotter.camera_position = camera
    else:
        plotter.view_isometric()
