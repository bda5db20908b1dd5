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
:mod:`.run`, and the files :mod:`.files` (LAS 1.4 through laspy, HDF5 through h5py).

Conventions: monostatic, received power in photoelectrons, one bounce, flat two-sided
normals (:data:`~meshladar.scan.points.CONVENTIONS`, recorded in every result's ``info``).
"""

from .footprint import ScanBeam
from .geiger import GeigerMode, coates
from .instrument import Detector, ScanSensor
from .patterns import PATTERNS, ScanPattern, flash, oscillating, raster, risley, rotating
from .platforms import Platform
from .points import POINT_DTYPE, POINT_FIELDS, PointCloud
from .run import scan
from .files import read_hdf5, read_las, write_hdf5, write_las

__all__ = ["scan", "PATTERNS", "ScanPattern", "raster", "rotating", "oscillating", "risley", "flash",
           "Platform", "ScanBeam", "ScanSensor", "Detector", "PointCloud", "POINT_DTYPE",
           "POINT_FIELDS", "GeigerMode", "coates", "write_las", "read_las", "write_hdf5", "read_hdf5"]
