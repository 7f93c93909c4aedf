"""The python3-fpp Debian package imports on its own: built by the target
package-python3-fpp (about 2 s once the module is built), extracted with
dpkg-deb -x into a temporary folder, and imported by a fresh python3 whose
path holds the extracted dist-packages and not the build folder; one
function called there gives what the build folder's package gives."""

import ast
import glob
import os
import shutil
import subprocess
import sys

import pytest

import fpp
from conftest import run


def test_the_deb_imports_from_its_extracted_files_alone(tmp_root, sim_capture):
    cmake, build = os.environ.get("FPP_CMAKE"), os.environ.get("FPP_BUILD_DIR")
    if not cmake or not build:
        pytest.fail("FPP_CMAKE and FPP_BUILD_DIR are not set (run through ctest -R Python)")
    if not shutil.which("dpkg-deb"):
        pytest.skip("dpkg-deb is missing")
    run([cmake, "--build", build, "--target", "package-python3-fpp"], timeout=120)
    debs = glob.glob(os.path.join(build, "python3-fpp_*.deb"))
    assert len(debs) == 1, debs
    root = os.path.join(tmp_root, "deb-root")
    run(["dpkg-deb", "-x", debs[0], root])
    dist = os.path.join(root, "usr", "lib", "python3", "dist-packages")
    assert os.path.isfile(os.path.join(dist, "fpp", "__init__.py"))
    assert glob.glob(os.path.join(dist, "fpp", "_fpp*.so"))

    probe = ("import sys, fpp\n"
             "r = fpp.decode(fpp.read_capture(sys.argv[1]))\n"
             "print(fpp.__file__)\n"
             "print(fpp._fpp.__file__)\n"
             "print(r.decoded, r.method_x)\n"
             "print([p for p in sys.path if p])\n")
    env = {"PATH": "/usr/bin:/bin", "PYTHONPATH": dist, "PYTHONDONTWRITEBYTECODE": "1",
           "HOME": tmp_root}
    r = subprocess.run([sys.executable, "-s", "-c", probe, sim_capture], cwd=root, env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    module, compiled, figures, path = r.stdout.splitlines()
    assert module.startswith(dist + os.sep) and compiled.startswith(dist + os.sep)
    built = os.path.join(build, "python")  # the build folder's package
    on_path = ast.literal_eval(path)
    assert built not in on_path and os.path.realpath(built) not in on_path
    here = fpp.decode(fpp.read_capture(sim_capture))
    assert figures == f"{here.decoded} {here.method_x}" and here.decoded > 0
