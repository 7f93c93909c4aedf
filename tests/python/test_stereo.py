"""fpp.StereoCalibration (ours, SLStudio's, SLMaster's files) and its SV
reconstruction against fpp-calib reconstruct --calib on the same real
captures (../shared/datasets): bitwise equal points."""

import os

import numpy as np
import pytest

import fpp

from conftest import dataset, run


def cli_points(calib_exe, tmp_root, capture, calib, name, fmt="auto"):
    out = os.path.join(tmp_root, name + ".ply")
    run([calib_exe, "reconstruct", capture, "--calib", calib, "--calib-format", fmt,
         "--smooth", "0", "--out", out])
    return fpp.read_ply(out)


@pytest.fixture(scope="module")
def slstudio():
    capture = dataset("slstudio", "skull_2x3")
    calib = dataset("slstudio", "calibration", "calibration.xml")
    return capture, calib, fpp.decode(fpp.read_capture(capture))


def test_slstudio_calibration_reconstructs_as_fpp_calib(slstudio, calib_exe, tmp_root):
    capture, calib, decoded = slstudio
    s = fpp.StereoCalibration.load(calib)
    assert s.format == "slstudio" and s.camera_matrix.shape == (3, 3)
    assert s.camera_matrix[2, 2] == 1 and s.camera_matrix[0, 0] > 1000
    cloud = s.reconstruct(decoded)
    assert cloud.stats["axes"] == "x" and cloud.stats["points"] == cloud.count_points()
    ref = cli_points(calib_exe, tmp_root, capture, calib, "cli-slstudio")
    assert cloud.count_points() > 350000  # of 401,197 decoded
    assert np.array_equal(cloud.xyz, ref.xyz, equal_nan=True)
    z = cloud.xyz[..., 2][cloud.valid]
    assert 300 < np.median(z) < 600  # the skull, mm in front of the camera


def test_our_format_saved_and_loaded_reconstructs_the_same(slstudio, calib_exe, tmp_root):
    capture, calib, decoded = slstudio
    saved = os.path.join(tmp_root, "slstudio-as-fpp.yaml")
    fpp.StereoCalibration.load(calib).save(saved)
    ours = fpp.StereoCalibration.load(saved)
    assert ours.format == "fpp"
    assert np.allclose(ours.R, fpp.StereoCalibration.load(calib).R, atol=1e-12)
    ref = cli_points(calib_exe, tmp_root, capture, saved, "cli-fpp-format")
    assert np.array_equal(ours.reconstruct(decoded, axes="x").xyz, ref.xyz, equal_nan=True)


def test_slmaster_calibration_reconstructs_as_fpp_calib(calib_exe, tmp_root):
    capture = dataset("slmaster", "monocular")
    calib = os.path.join(capture, "caliInfo.yml")
    s = fpp.StereoCalibration.load(calib, format="slmaster")
    assert s.format == "slmaster" and s.camera_size is None  # SLMaster records no sizes
    cloud = s.reconstruct(fpp.decode(fpp.read_capture(capture)))
    assert s.camera_size == fpp.read_capture(capture).camera  # taken from the decode
    ref = cli_points(calib_exe, tmp_root, capture, calib, "cli-slmaster", "slmaster")
    assert cloud.count_points() > 10000
    assert np.array_equal(cloud.xyz, ref.xyz, equal_nan=True)


def test_bad_calibration_files_and_arguments(tmp_root, slstudio):
    bad = os.path.join(tmp_root, "bad-calib.yaml")
    with open(bad, "w") as f:
        f.write("%YAML:1.0\n---\nformat: fpp-stereo/1\ncamera_size: [800, 600]\n")
    with pytest.raises(fpp.InputError) as e:
        fpp.StereoCalibration.load(bad)
    assert e.value.file == bad and "not a recognised calibration" in str(e.value)
    with pytest.raises(fpp.InputError) as e:
        fpp.StereoCalibration.load(bad, format="photoneo")
    assert e.value.field == "format"
    _, calib, decoded = slstudio
    with pytest.raises(fpp.InputError) as e:
        fpp.StereoCalibration.load(calib).reconstruct(decoded, axes="z")
    assert e.value.field == "axes"


def test_raw_arrays_reconstruct_as_the_decode_result(slstudio):
    _, calib, decoded = slstudio
    s = fpp.StereoCalibration.load(calib)
    ref = s.reconstruct(decoded)
    proj_x = np.array(decoded.proj_x)
    for args, kwargs in [((proj_x,), {}), ((proj_x,), {"mask": decoded.mask}),
                         ((proj_x.astype(np.float64),), {"mask": decoded.flags & 1}),
                         ((np.asfortranarray(proj_x),), {"projector": decoded.projector})]:
        cloud = s.reconstruct(*args, **kwargs)
        assert np.array_equal(cloud.xyz, ref.xyz, equal_nan=True)
        assert cloud.stats == ref.stats
    # a mask drops pixels as the decode's own would: the left half here
    half = decoded.mask.copy()
    half[:, half.shape[1] // 2:] = False
    cloud = s.reconstruct(proj_x, mask=half)
    left = half.shape[1] // 2
    assert np.array_equal(cloud.xyz[:, :left], ref.xyz[:, :left], equal_nan=True)
    assert np.isnan(cloud.xyz[:, left:]).all()
    assert 0 < cloud.count_points() < ref.count_points()
    assert np.array_equal(proj_x, decoded.proj_x, equal_nan=True)  # the caller's array untouched
    # bad arrays: TypeError naming the argument
    with pytest.raises(TypeError, match="mask"):
        s.reconstruct(proj_x, mask=half[:-1])
    with pytest.raises(TypeError, match="proj_y"):
        s.reconstruct(proj_x, proj_x[:, :-1])
    with pytest.raises(TypeError, match="proj_x"):
        s.reconstruct(proj_x.astype(str))
    with pytest.raises(TypeError, match="proj_y"):
        s.reconstruct(decoded, proj_x)
