"""fpp.decode against fpp-calib decode on the same capture: bitwise equal."""

import os
import re
import threading
import time

import numpy as np
import pytest

import fpp

from conftest import run


def equal(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)


def test_decode_equals_fpp_calib_decode(sim_capture, cli_decode):
    r = fpp.decode(fpp.read_capture(sim_capture))
    assert r.camera == (800, 600)
    assert r.method_x == r.method_y == "complementary-gray"
    for name in ("proj_x", "proj_y", "modulation"):
        assert equal(getattr(r, name), fpp.read_image(os.path.join(cli_decode, name + ".tiff")))
    assert equal(r.flags, fpp.read_image(os.path.join(cli_decode, "flags.png")))
    assert np.array_equal(r.mask, fpp.read_image(os.path.join(cli_decode, "mask.png")) == 255)
    # The report's figures are decode.md's.
    md = open(os.path.join(cli_decode, "decode.md")).read()
    lit = re.search(r"- lit: (\d+) of (\d+)", md)
    decoded = re.search(r"- decoded: (\d+) of (\d+) lit pixels", md)
    assert (r.lit, r.pixels) == (int(lit.group(1)), int(lit.group(2)))
    assert r.decoded == int(decoded.group(1)) == int(r.mask.sum())
    assert r.decoded + sum(r.dropped.values()) == r.pixels == 800 * 600
    assert 0.9 < r.coverage_of_lit <= 1.0
    assert not r.failed and not r.inconsistent and r.consistency == ""
    # Against the simulator's truth: sub-pixel.
    truth = fpp.read_capture(sim_capture).truth["projector"][..., 0]
    ok = r.mask & np.isfinite(truth)
    assert np.sqrt(np.mean((r.proj_x[ok] - truth[ok]) ** 2)) < 0.2


def test_arrays_are_views_of_the_result_not_copies(sim_capture):
    r = fpp.decode(fpp.read_capture(sim_capture))
    a, b = r.proj_x, r.proj_x
    assert a.ctypes.data == b.ctypes.data and not a.flags.owndata and not a.flags.writeable
    assert r.flags.dtype == np.uint8 and r.mask.dtype == bool
    del r  # the arrays keep the result alive
    assert np.isfinite(a).sum() > 100000


def test_frames_with_a_sequence_decode_as_the_capture(sim_capture):
    cap = fpp.read_capture(sim_capture)
    r1 = fpp.decode(cap)
    frames = [np.asfortranarray(f) for f in cap.frames]  # another layout: copied
    r2 = fpp.decode(frames, cap.manifest["sequence"], projector=cap.projector)
    assert equal(r1.proj_x, r2.proj_x) and equal(r1.proj_y, r2.proj_y)
    assert equal(r1.flags, r2.flags)


def test_contiguous_frames_are_read_in_place_and_kept_alive(sim_capture):
    cap = fpp.read_capture(sim_capture)
    r1 = fpp.decode(cap)
    frames = [np.array(f) for f in cap.frames]  # writeable, contiguous: borrowed, not copied
    r2 = fpp.decode(frames, cap.manifest["sequence"], projector=cap.projector)
    del frames  # the result keeps the arrays it read
    assert equal(r1.proj_x, r2.proj_x) and equal(r1.proj_y, r2.proj_y)
    assert equal(r1.modulation, r2.modulation) and equal(r1.flags, r2.flags)
    assert r2.lit == r1.lit and r2.decoded == r1.decoded  # the report reads them after
    # 16-bit frames (8-bit samples << 4, found to use 12 bits): the same field
    wide = [np.array(f, dtype=np.uint16) << 4 for f in cap.frames]
    r3 = fpp.decode(wide, cap.manifest["sequence"], projector=cap.projector)
    assert r3.full_scale == 4095
    assert int(r3.mask.sum()) > 0.9 * int(r1.mask.sum())


def test_options_change_the_decode_as_on_the_command_line(sim_capture, calib_exe, tmp_root):
    cap = fpp.read_capture(sim_capture)
    out = os.path.join(tmp_root, "cli-decode-minmod")
    run([calib_exe, "decode", sim_capture, "--out", out, "--min-modulation", "0.2",
         "--threads", "1"], ok=(0, 3, 5))
    r = fpp.decode(cap, min_modulation=0.2, threads=1, accept_inconsistent=True)
    assert equal(r.flags, fpp.read_image(os.path.join(out, "flags.png")))
    assert r.decoded < fpp.decode(cap).decoded


@pytest.mark.parametrize("option, value, cli", [
    ("min_modulation", 1.5, ["--min-modulation", "1.5"]),
    ("min_modulation", -0.1, ["--min-modulation", "-0.1"]),
    ("threads", -1, ["--threads", "-1"]),
])
def test_bad_options_are_refused_with_fpp_calibs_message(sim_capture, calib_exe, tmp_root,
                                                         option, value, cli):
    r = run([calib_exe, "decode", sim_capture, "--out", os.path.join(tmp_root, "never")] + cli,
            ok=(2,))
    cli_what = re.search(r"command line: --[a-z-]+: (.*)", r.stderr).group(1).strip()
    with pytest.raises(fpp.InputError) as e:
        fpp.decode(fpp.read_capture(sim_capture), **{option: value})
    assert isinstance(e.value, ValueError)
    assert e.value.file == "fpp.decode" and e.value.field == option
    assert str(e.value) == f"fpp.decode: {option}: {cli_what}"


def test_a_black_capture_raises_decode_error_with_the_result(sim_capture):
    cap = fpp.read_capture(sim_capture)
    black = [np.zeros((600, 800), np.uint8) for _ in range(len(cap))]
    with pytest.raises(fpp.DecodeError) as e:
        fpp.decode(black, cap.manifest["sequence"], projector=cap.projector)
    assert e.value.reason == "failed"
    assert e.value.result.decoded == 0 and e.value.result.proj_x.shape == (600, 800)


def test_the_gil_is_released_while_decoding(sim_capture):
    """The main thread keeps running Python while another thread decodes: its
    turns between the moments just before and just after the call are
    counted (with the GIL held throughout, there would be none, or the few
    of one switch interval before the call)."""
    cap = fpp.read_capture(sim_capture)
    cap.frames  # read before
    span = []

    def work():
        t0 = time.perf_counter()
        fpp.decode(cap, threads=1)
        span.extend([t0, time.perf_counter()])

    worker = threading.Thread(target=work)
    turns = []
    worker.start()
    while worker.is_alive():
        turns.append(time.perf_counter())
        worker.join(0.0005)  # gives the GIL back for a moment
    t0, t1 = span
    assert sum(t0 < t < t1 for t in turns) >= 20


def test_help_says_how_to_call_it():
    doc = fpp.decode.__doc__
    for word in ("min_modulation", "threads", "correct_phase_error", "accept_inconsistent",
                 "projector px", "InputError", "DecodeError"):
        assert word in doc
