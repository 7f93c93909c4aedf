#!/usr/bin/env python3
"""The Python package's overhead on a decode (issue 34's target: fpp.decode
within 1.1x of the C++ decode's time).

A 1600 x 1200 capture of the paper's rig, 8-step phase (period 20) with
complementary Gray code in x, white and black (fpp-calib simulate --sequence
gray-x), read once; then, in the same process on the same frames in memory:
  cpp          fpp::decode alone, timed in C++ with no Python object made
               (fpp._fpp._cpp_decode_seconds)
  python       fpp.decode(capture, check=False): the same from Python, its
               arrays made (the target's ratio: python / cpp)
  cpp checked  fpp::decode and the report's statistics, diagnosis and
               consistency check (fpp-calib decode's judgement), in C++
  python checked  fpp.decode(capture), the default: the same from Python
  frames       fpp.decode(frames, sequence, projector=..., check=False): the
               frames as NumPy arrays, read in place (borrowed, not copied)
Best of --repetitions runs each (a shared machine: the least disturbed run),
the runs interleaved. Prints the ratios; no threshold is judged here.

usage: bench_python_decode.py --calib FPP_CALIB --rig board/sim/paper-rig.yaml
       --tmp DIR [--repetitions N]   (PYTHONPATH=<build>/python)
"""

import argparse
import os
import shutil
import subprocess
import sys
import time

import fpp


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calib", required=True, help="fpp-calib")
    parser.add_argument("--rig", required=True, help="board/sim/paper-rig.yaml")
    parser.add_argument("--tmp", required=True, help="a folder for the capture (emptied)")
    parser.add_argument("--repetitions", type=int, default=10)
    parser.add_argument("--threads", type=int, default=0, help="0 = all cores")
    args = parser.parse_args()

    shutil.rmtree(args.tmp, ignore_errors=True)
    os.makedirs(args.tmp)
    folder = os.path.join(args.tmp, "capture")
    subprocess.run([args.calib, "simulate", "--rig", args.rig, "--scene", "composite",
                    "--sequence", "gray-x", "--out", folder], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    capture = fpp.read_capture(folder)
    frames = list(capture.frames)  # read once: in memory from here on
    sequence, projector = capture.manifest["sequence"], capture.projector
    print(f"capture: {capture.camera[0]}x{capture.camera[1]}, {len(frames)} frames, "
          f"{[b['pattern'] for b in sequence]}")

    best = {"cpp": [], "python": [], "cpp checked": [], "python checked": [], "frames": []}

    def timed(key, call):
        t = time.perf_counter()
        r = call()
        r.proj_x, r.modulation, r.flags  # the arrays made, as a user would
        best[key].append(time.perf_counter() - t)

    for _ in range(max(1, args.repetitions)):
        best["cpp"] += fpp._fpp._cpp_decode_seconds(capture, 1, args.threads, False)
        timed("python", lambda: fpp.decode(capture, threads=args.threads, check=False))
        best["cpp checked"] += fpp._fpp._cpp_decode_seconds(capture, 1, args.threads, True)
        timed("python checked", lambda: fpp.decode(capture, threads=args.threads))
        timed("frames", lambda: fpp.decode(frames, sequence, projector=projector,
                                           threads=args.threads, check=False))
    times = {k: min(v) for k, v in best.items()}
    print(f"{'':15} {'best ms':>9} {'median ms':>10}   ({len(best['cpp'])} runs each)")
    for k, v in best.items():
        print(f"{k:15} {1e3 * times[k]:9.1f} {1e3 * sorted(v)[len(v) // 2]:10.1f}")
    print(f"ratio python / cpp:                 {times['python'] / times['cpp']:.3f}  "
          "(target <= 1.1)")
    print(f"ratio python checked / cpp checked: "
          f"{times['python checked'] / times['cpp checked']:.3f}")
    print(f"ratio frames / cpp:                 {times['frames'] / times['cpp']:.3f}  "
          "(NumPy frames, borrowed)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
