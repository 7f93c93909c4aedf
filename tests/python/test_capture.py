"""fpp.read_capture / write_capture / Capture against the C++ reader's files."""

import os

import numpy as np
import pytest

import fpp


def test_read_capture_reads_the_manifest_now_and_the_frames_on_first_use(sim_capture):
    cap = fpp.read_capture(sim_capture)
    assert not cap.loaded
    m = cap.manifest
    assert m["camera"] == {"width": 800, "height": 600}
    assert cap.camera == (800, 600) and cap.projector == (m["projector"]["width"],
                                                          m["projector"]["height"])
    # gray-xy: white, black, then 8-step phase and complementary Gray code per axis
    assert [b["pattern"] for b in m["sequence"]] == ["white", "black", "phase", "gray", "phase",
                                                     "gray"]
    assert m["sequence"][2]["steps"] == 8 and m["sequence"][2]["period"] == 20
    assert len(cap) == len(m["frames"]) > 20
    frames = cap.frames
    assert cap.loaded and len(frames) == len(cap)
    for name, frame in zip(m["frames"], frames):
        assert frame.dtype == np.uint8 and frame.shape == (600, 800)
        assert not frame.flags.writeable
        assert np.array_equal(frame, fpp.read_image(os.path.join(sim_capture, name)))
    # the same memory on every access: views of the capture, not copies
    again = cap.frames
    assert all(a.ctypes.data == b.ctypes.data for a, b in zip(frames, again))
    assert cap.bits_in_use == 8


def test_truth_is_the_simulators(sim_capture):
    cap = fpp.read_capture(sim_capture)
    truth = cap.truth
    assert truth["xyz"].shape == (600, 800, 3) and truth["xyz"].dtype == np.float32
    assert truth["projector"].shape == (600, 800, 2)
    z = truth["xyz"][..., 2]
    finite = np.isfinite(z)
    assert finite.mean() > 0.5
    assert 300 < np.median(z[finite]) < 700  # mm in front of the camera (the paper's volume)


def test_write_capture_round_trips_frames_manifest_and_truth(sim_capture, tmp_root):
    cap = fpp.read_capture(sim_capture)
    out = os.path.join(tmp_root, "written-copy")
    fpp.write_capture(out, cap.frames, manifest=cap.manifest, truth=cap.truth)
    back = fpp.read_capture(out)
    assert back.manifest == cap.manifest
    for a, b in zip(cap.frames, back.frames):
        assert np.array_equal(a, b)
    assert np.array_equal(back.truth["xyz"], cap.truth["xyz"], equal_nan=True)


def test_write_capture_from_a_sequence_and_16_bit_frames(tmp_root):
    rng = np.random.default_rng(1)
    frames = [rng.integers(0, 4096, (48, 64), dtype=np.uint16) for _ in range(3)]
    seq = [{"pattern": "phase", "axis": "x", "period": 64, "steps": 3}]
    out = os.path.join(tmp_root, "written-16")
    fpp.write_capture(out, frames, sequence=seq, projector=(64, 32), bit_depth=12)
    back = fpp.read_capture(out)
    assert back.manifest["bit_depth"] == 12 and back.manifest["frames"][0] == "000.png"
    assert back.bits_in_use == 12
    assert all(np.array_equal(a, b) for a, b in zip(frames, back.frames))
    # Nothing is left behind by a refusal, and the folder must be new.
    with pytest.raises(fpp.InputError) as e:
        fpp.write_capture(os.path.join(tmp_root, "written-bad"), frames[:2], sequence=seq,
                          projector=(64, 32))
    assert e.value.field == "frames"
    assert "2 frames listed but the sequence's blocks add up to 3 frames" in str(e.value)
    assert not os.path.exists(os.path.join(tmp_root, "written-bad"))


def test_from_frames_keeps_the_frames_and_the_sequence(sim_capture):
    cap = fpp.read_capture(sim_capture)
    mem = fpp.Capture.from_frames(list(cap.frames), cap.manifest["sequence"], cap.projector)
    assert mem.loaded and len(mem) == len(cap) and str(mem.path) == "<memory>"
    assert mem.manifest["sequence"] == cap.manifest["sequence"]
    assert all(np.array_equal(a, b) for a, b in zip(cap.frames, mem.frames))
