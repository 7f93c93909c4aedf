"""fpp from Python: fringe-projection decoding, reconstruction and the scanner.

The compiled part (fpp._fpp) binds fpp's C++ libraries, so that Python decodes
and reconstructs exactly as fpp-calib and the scanner do:

    read_capture, write_capture, Capture   capture sets (capture-set.md)
    read_image                             frame files and float TIFFs as fpp reads them
    decode, DecodeResult                   projector coordinates per camera pixel
    Table                                  coefficient tables (.fpt) and their kernel
    StereoCalibration                      stereo calibrations and SV reconstruction
    read_ply, write_ply, Cloud, to_open3d  organised point clouds
    Scanner                                the scanner's HTTP API (pure Python)
    InputError, DecodeError, ScannerError  errors

Conventions: camera frame = world frame, millimetres; pixel centres on integer
coordinates (OpenCV's), for camera and projector alike; arrays are indexed
[row, column] = [y, x], sizes are given as (width, height).
"""

from ._fpp import (  # noqa: F401
    Capture,
    DecodeError,
    DecodeResult,
    InputError,
    StereoCalibration,
    Table,
    decode,
    read_capture,
    read_image,
    write_capture,
)
from .cloud import Cloud, read_ply, to_open3d, write_ply  # noqa: F401
from .scanner import Scanner, ScannerError  # noqa: F401

__all__ = [
    "Capture", "Cloud", "DecodeError", "DecodeResult", "InputError", "Scanner",
    "ScannerError", "StereoCalibration", "Table", "decode", "read_capture", "read_ply",
    "read_image", "to_open3d", "write_capture", "write_ply",
]
