"""fpp.Table, fpp.read_ply / write_ply and to_open3d against fpp-calib
reconstruct --table on the same capture: bitwise equal points."""

import os
import shutil

import numpy as np
import pytest

import fpp

from conftest import run


@pytest.fixture(scope="module")
def decoded(sim_capture):
    return fpp.decode(fpp.read_capture(sim_capture))


@pytest.fixture(scope="module")
def cli_cloud(tmp_root, calib_exe, sim_capture, truth_table):
    out = os.path.join(tmp_root, "cli-table.ply")
    run([calib_exe, "reconstruct", sim_capture, "--table", truth_table, "--smooth", "0",
         "--out", out])
    return out


def test_table_loads_mapped_with_its_header(truth_table):
    t = fpp.Table.load(truth_table)
    assert t.mapped and t.camera == (800, 600) and t.phase_axis == "x"
    assert t.model in ("polynomial", "ray", "rational")
    assert not fpp.Table.load(truth_table, map=False).mapped


def test_apply_equals_fpp_calib_reconstruct(truth_table, decoded, cli_cloud):
    xyz = fpp.Table.load(truth_table).apply(decoded.proj_x)
    assert xyz.shape == (600, 800, 3) and xyz.dtype == np.float32
    cloud = fpp.read_ply(cli_cloud)
    assert cloud.organised and cloud.xyz.shape == (600, 800, 3)
    assert np.array_equal(xyz, cloud.xyz, equal_nan=True)
    assert cloud.count_points() > 200000
    # quality and intensity are the decode's modulation and mean where there is a point
    v = cloud.valid
    assert np.array_equal(cloud.quality[v], decoded.modulation[v])
    assert np.array_equal(cloud.intensity[v], decoded.mean[v])


def test_apply_returns_the_kernels_array_without_a_copy(truth_table, decoded):
    xyz = fpp.Table.load(truth_table).apply(decoded.proj_x)
    assert not xyz.flags.owndata and xyz.base is not None and xyz.flags.writeable
    assert xyz.flags.c_contiguous


def test_apply_converts_safe_inputs_and_refuses_others(truth_table, decoded):
    table = fpp.Table.load(truth_table)
    ref = table.apply(decoded.proj_x)
    as64 = decoded.proj_x.astype(np.float64)
    assert np.array_equal(table.apply(as64), ref, equal_nan=True)
    strided = np.asfortranarray(decoded.proj_x)
    assert np.array_equal(table.apply(strided), ref, equal_nan=True)
    with pytest.raises(TypeError, match=r"proj_x: expected an \(H, W\) array .*600, 800.*"
                                        r"got shape \(600, 799\)"):
        table.apply(decoded.proj_x[:, :799])
    with pytest.raises(TypeError, match="proj_x: .*got dtype complex64"):
        table.apply(decoded.proj_x.astype(np.complex64))
    with pytest.raises(TypeError, match="proj_x"):
        table.apply("not an array")


def test_apply_with_the_coordinate_sigma_gives_sigma_z(truth_table, decoded):
    sigma = np.full((600, 800), 0.05, np.float32)
    xyz, sigma_z = fpp.Table.load(truth_table).apply(decoded.proj_x, coordinate_sigma=sigma)
    v = np.isfinite(xyz[..., 2])
    assert np.isfinite(sigma_z[v]).all() and np.isnan(sigma_z[~v]).all()
    assert 0.001 < np.median(sigma_z[v]) < 0.5  # mm: 0.05 projector px through the rig


def test_a_damaged_table_is_an_input_error_naming_the_tile(truth_table, tmp_root):
    bad = os.path.join(tmp_root, "damaged.fpt")
    shutil.copyfile(truth_table, bad)
    with open(bad, "r+b") as f:
        f.seek(os.path.getsize(bad) // 2)
        byte = f.read(1)
        f.seek(-1, os.SEEK_CUR)
        f.write(bytes([byte[0] ^ 0xFF]))
    with pytest.raises(fpp.InputError) as e:
        fpp.Table.load(bad)
    assert "crc" in e.value.field and e.value.file == bad
    with pytest.raises(fpp.InputError):
        fpp.Table.load(truth_table, camera=(640, 480))


def test_write_ply_then_read_ply_keeps_pixels_quality_and_sigma(truth_table, decoded, tmp_root):
    sigma = np.full((600, 800), 0.05, np.float32)
    xyz, sigma_z = fpp.Table.load(truth_table).apply(decoded.proj_x, coordinate_sigma=sigma)
    cloud = fpp.Cloud(xyz, quality=decoded.modulation, intensity=decoded.mean, sigma_z=sigma_z)
    path = os.path.join(tmp_root, "py.ply")
    fpp.write_ply(path, cloud, comments=["made by the Python test"])
    back = fpp.read_ply(path)
    assert back.organised and back.comments[-1] == "made by the Python test"
    v = cloud.valid
    assert np.array_equal(back.xyz, xyz, equal_nan=True)
    assert np.array_equal(back.quality[v], decoded.modulation[v])
    assert np.array_equal(back.sigma_z[v], sigma_z[v])
    assert np.isnan(back.quality[~v]).all()


def test_to_open3d_and_open3ds_own_reader(truth_table, decoded, cli_cloud):
    o3d = pytest.importorskip("open3d")
    cloud = fpp.read_ply(cli_cloud)
    made = fpp.to_open3d(cloud)
    assert len(made.points) == cloud.count_points()
    assert np.allclose(np.asarray(made.points), cloud.points().astype(np.float64))
    assert np.asarray(made.colors).shape == (cloud.count_points(), 3)
    read = o3d.io.read_point_cloud(cli_cloud)
    assert len(read.points) == cloud.count_points()
    assert np.array_equal(np.asarray(read.points).astype(np.float32), cloud.points())


def test_read_ply_refuses_what_is_not_a_ply(tmp_root):
    path = os.path.join(tmp_root, "not.ply")
    with open(path, "w") as f:
        f.write("hello\n")
    with pytest.raises(fpp.InputError) as e:
        fpp.read_ply(path)
    assert e.value.file == path
