"""Organised point clouds: one slot per camera pixel (fpp/point_cloud.hpp)."""

import os

import numpy as np

from . import _fpp


class Cloud:
    """A point cloud, organised (one slot per camera pixel) or a flat list.

    xyz        (H, W, 3) float32: X, Y, Z per camera pixel, camera frame, mm,
               NaN where there is no point; (N, 3) for a cloud read from a PLY
               file without pixel indices
    quality    (H, W) float32 fringe modulation B (camera DN), or None
    intensity  (H, W) float32 mean intensity A (camera DN), or None
    sigma_z    (H, W) float32 predicted standard deviation of Z (mm), or None
    pixel      (N,) uint32 camera pixel index (row * width + column) of a flat
               cloud that has them without an organised size, else None
    comments   the PLY file's comment lines
    """

    def __init__(self, xyz, quality=None, intensity=None, sigma_z=None, pixel=None,
                 comments=()):
        self.xyz = xyz
        self.quality = quality
        self.intensity = intensity
        self.sigma_z = sigma_z
        self.pixel = pixel
        self.comments = list(comments)

    @property
    def organised(self):
        """Whether xyz is (H, W, 3), one slot per camera pixel."""
        return self.xyz.ndim == 3

    @property
    def valid(self):
        """Boolean array: True where the slot holds a point (X, Y, Z all finite)."""
        return np.isfinite(self.xyz).all(axis=-1)

    def count_points(self):
        """The number of slots holding a point."""
        return int(self.valid.sum())

    def points(self):
        """The points alone, an (N, 3) float32 array (row-major order), mm."""
        return self.xyz[self.valid]

    def __repr__(self):
        shape = "x".join(str(n) for n in self.xyz.shape[:-1])
        return f"<fpp.Cloud {shape}: {self.count_points()} points>"


def read_ply(path):
    """Reads a PLY point cloud (binary little-endian, as fpp writes it).

    An organised file (obj_info organised_width/height and a `pixel` vertex
    property, as fpp-calib reconstruct and the scanner write) comes back
    organised: every point in its camera pixel, (H, W, 3) xyz, NaN (and NaN
    quality, intensity, sigma_z) in the pixels without a point. Any other
    file: a flat (N, 3) cloud. Camera frame, mm.

    Returns an fpp.Cloud. Raises fpp.InputError naming the file for anything
    that is not such a PLY file (another encoding, no x/y/z, truncated body,
    a pixel index outside the organised size).
    """
    d = _fpp._read_ply(os.fspath(path))
    return Cloud(d["xyz"], d["quality"], d["intensity"], d["sigma_z"], d["pixel"],
                 d["comments"])


def write_ply(path, cloud, comments=None):
    """Writes an organised cloud as PLY, atomically (fpp's layout).

    Only the slots with a point are written, in row-major order, each with x,
    y, z (mm), quality and intensity (DN; 0 when the cloud has none), sigma_z
    (mm; when the cloud has it) and the index of its camera pixel, with the
    organised size in obj_info lines: fpp.read_ply gives the organised cloud
    back, and Open3D, CloudCompare and MeshLab read the file.

    cloud: an fpp.Cloud with (H, W, 3) xyz, or an (H, W, 3) array alone.
    comments: comment lines (default: the cloud's own).
    Raises TypeError for arrays of the wrong shape, OSError when it cannot write.
    """
    if not isinstance(cloud, Cloud):
        cloud = Cloud(cloud)
    if comments is None:
        comments = cloud.comments
    _fpp._write_ply(os.fspath(path), cloud.xyz, cloud.quality, cloud.intensity, cloud.sigma_z,
                    [str(c) for c in comments])


def to_open3d(cloud, colour="intensity"):
    """The cloud's points as an open3d.geometry.PointCloud (camera frame, mm).

    colour: 'intensity' or 'quality' (grey, scaled to the cloud's largest
    value), or None for no colours. Needs Open3D (Debian's python3-open3d);
    ImportError otherwise.
    """
    import open3d  # noqa: PLC0415 (optional dependency)

    if not isinstance(cloud, Cloud):
        cloud = Cloud(cloud)
    valid = cloud.valid
    made = open3d.geometry.PointCloud()
    made.points = open3d.utility.Vector3dVector(cloud.xyz[valid].astype(np.float64))
    values = None
    if colour == "intensity":
        values = cloud.intensity
    elif colour == "quality":
        values = cloud.quality
    elif colour is not None:
        raise ValueError(f"colour: expected 'intensity', 'quality' or None, got {colour!r}")
    if values is not None:
        v = np.nan_to_num(values[valid].astype(np.float64))
        top = v.max() if v.size and v.max() > 0 else 1.0
        grey = np.clip(v / top, 0.0, 1.0)
        made.colors = open3d.utility.Vector3dVector(np.repeat(grey[:, None], 3, axis=1))
    return made
