"""Shared fixtures of the Python package's tests (tests/CMakeLists.txt runs
them with pytest: `ctest -R Python`).

The programs and folders come from the environment CTest sets:
  FPP_CALIB_EXE    fpp-calib: the C++ results the package must equal
  FPP_SCANNER_EXE  fpp-scanner (with the virtual scanner) for the client's tests
  FPP_TABLE_TOOL   fpp_test_truth_table: a sim rig's true coefficient table
  FPP_SOURCE_DIR   the source tree (board/ for the sim boards and rigs)
  FPP_SHARED_DIR   ../shared (datasets/: SLStudio's and SLMaster's captures)
  FPP_TEST_TMP     a folder for this run (emptied first)
and the package itself from PYTHONPATH (<build>/python).
"""

import os
import shutil
import subprocess

import pytest

SOURCE = os.environ.get("FPP_SOURCE_DIR",
                        os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
BOARDS = os.path.join(SOURCE, "board")
SHARED = os.environ.get("FPP_SHARED_DIR", os.path.join(SOURCE, "..", "shared"))
DATASETS = os.path.join(SHARED, "datasets")


def program(name):
    path = os.environ.get(name)
    if not path or not os.path.exists(path):
        pytest.fail(f"{name} is not set to a built program (run through ctest -R Python)")
    return path


def run(cmd, ok=(0,), timeout=300):
    """Runs a program; its result (returncode, stdout, stderr). Fails the test
    on an exit status outside `ok`."""
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if r.returncode not in ok:
        pytest.fail(f"{' '.join(cmd)} exited {r.returncode}:\n{r.stdout}\n{r.stderr}")
    return r


def dataset(*parts):
    """A real capture of ../shared/datasets; skipped when absent (failed in CI)."""
    path = os.path.join(DATASETS, *parts)
    if not os.path.exists(path):
        if os.environ.get("CI") == "true":
            pytest.fail(f"{path} is missing (the real-data tests need ../shared/datasets)")
        pytest.skip(f"{path} is missing (../shared/datasets beside the checkout)")
    return path


@pytest.fixture(scope="session")
def tmp_root():
    root = os.environ.get("FPP_TEST_TMP")
    if not root:
        import tempfile
        root = tempfile.mkdtemp(prefix="fpp-python-")
    shutil.rmtree(root, ignore_errors=True)
    os.makedirs(root)
    return root


@pytest.fixture(scope="session")
def calib_exe():
    return program("FPP_CALIB_EXE")


@pytest.fixture(scope="session")
def sim_capture(tmp_root, calib_exe):
    """A simulated capture of the paper's rig with its effects, camera binned
    2 x 2 (800 x 600): white, black, 8-step phase and complementary Gray code
    in x and y, with ground truth."""
    out = os.path.join(tmp_root, "sim-capture")
    run([calib_exe, "simulate", "--rig", os.path.join(BOARDS, "sim", "paper-rig-effects.yaml"),
         "--binning", "2", "--scene", "composite", "--sequence", "gray-xy", "--out", out])
    return out


@pytest.fixture(scope="session")
def cli_decode(tmp_root, calib_exe, sim_capture):
    """fpp-calib decode's outputs for the simulated capture."""
    out = os.path.join(tmp_root, "cli-decode")
    run([calib_exe, "decode", sim_capture, "--out", out])
    return out


@pytest.fixture(scope="session")
def truth_table(tmp_root):
    """The true coefficient table of the simulated rig (800 x 600 camera)."""
    out = os.path.join(tmp_root, "truth.fpt")
    run([program("FPP_TABLE_TOOL"), os.path.join(BOARDS, "sim", "paper-rig-effects.yaml"), "2",
         out])
    return out
