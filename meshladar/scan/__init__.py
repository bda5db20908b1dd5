"""The imaging ladar: scanners on platforms, per-pulse waveforms and multi-echo point
clouds with ground truth.

Where :func:`meshladar.simulate` answers what range profile a whole target gives from each
view, :func:`scan` answers what point cloud a scanner records: each pulse of a
:class:`ScanPattern` leaves at its own time from the sensor's pose on a :class:`Platform`,
its beam sampled by sub-rays (:class:`ScanBeam`), its echo weighed with the coatings'
BRDFs and the link budget, recorded as a waveform with the receiver's noise and searched
for returns (:class:`Detector`). Every return carries its ground truth (the part, face,
range and point its light came from). Layout: :mod:`.patterns`, :mod:`.platforms`,
:mod:`.footprint`, :mod:`.instrument`, :mod:`.cast`, :mod:`.echoes`, :mod:`.points`,
:mod:`.run`, and the files :mod:`.files` (LAS 1.4 through laspy, HDF5 through h5py) and
``npz`` (numpy's archive, no extra package), their formats by extension :mod:`.formats`.

Conventions: monostatic, received power in photoelectrons, one bounce, flat two-sided
normals (:data:`~meshladar.scan.points.CONVENTIONS`, recorded in every result's ``info``).
"""

from __future__ import annotations

from .._lazy import lazy_attributes as _lazy_attributes

__all__ = ["scan", "PATTERNS", "ScanPattern", "raster", "rotating", "oscillating", "risley",
           "flash", "Platform", "ScanBeam", "ScanSensor", "Detector", "PointCloud",
           "POINT_DTYPE", "POINT_FIELDS", "GeigerMode", "coates", "write_las", "read_las",
           "write_hdf5", "read_hdf5", "write_npz", "read_npz"]

#: Each public name's module: loaded on first use (``meshladar.scan.Platform``,
#: ``from meshladar.scan import scan``), so that the command line, which names this
#: package for every command, loads scipy's interpolation and special functions, numba's
#: Geiger-mode loops and the scan's kernels only when a scan runs.
_HOMES = {"ScanBeam": "footprint", "GeigerMode": "geiger", "coates": "geiger",
          "Detector": "instrument", "ScanSensor": "instrument", "PATTERNS": "patterns",
          "ScanPattern": "patterns", "flash": "patterns", "oscillating": "patterns",
          "raster": "patterns", "risley": "patterns", "rotating": "patterns",
          "Platform": "platforms", "POINT_DTYPE": "points", "POINT_FIELDS": "points",
          "PointCloud": "points", "scan": "run", "read_hdf5": "files", "read_las": "files",
          "write_hdf5": "files", "write_las": "files", "read_npz": "npz", "write_npz": "npz"}


#: The package's modules, also reached as attributes (``meshladar.scan.points``).
_SUBMODULES = ("patterns", "platforms", "footprint", "instrument", "cast", "echoes", "points",
               "run", "files", "foreign", "npz", "formats", "geiger", "moving")


__getattr__, __dir__ = _lazy_attributes(__name__, globals(), _HOMES, _SUBMODULES)
