"""Shared by the tests of the Python module: the repository, the command-line programs (to compare with),
and running them. The module comes from PYTHONPATH (ctest sets it to build/<preset>/python)."""
import json
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("SNH_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))


def program(variable):
    """The program named by an environment variable (ctest sets SNH_BIN and SNH_TETCLI), else skip."""
    path = os.environ.get(variable)
    if not path or not os.access(path, os.X_OK):
        pytest.skip(f"{variable} is not set to a program (the build has no programs: SNH_REPORT=OFF)")
    return path


def snh_cli(*args, check=True):
    """Runs snh with these arguments: (exit code, stdout, stderr)."""
    r = subprocess.run([program("SNH_BIN"), *map(str, args)], capture_output=True, text=True, timeout=120)
    if check and r.returncode != 0:
        raise AssertionError(f"snh {' '.join(map(str, args))} exited {r.returncode}: {r.stderr}")
    return r.returncode, r.stdout, r.stderr


def snh_json(*args):
    return json.loads(snh_cli(*args, "--json")[1])


def cli_error(*args):
    """The one-line error snh prints for bad input (exit 2), without its 'snh: error: ' prefix."""
    code, _, err = snh_cli(*args, check=False)
    assert code == 2, (code, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    prefix = "snh: error: "
    assert lines[0].startswith(prefix), lines[0]
    return lines[0][len(prefix):]


def read_obj_vertices(path):
    """The 'v' lines of an OBJ file as text triples (the program writes %.10g)."""
    return [line.split()[1:] for line in pathlib.Path(path).read_text().splitlines() if line.startswith("v ")]


def as_obj_text(positions):
    """Positions formatted as the OBJ writer does ({:.10g}, which Python's format spells the same)."""
    return [[format(float(c), ".10g") for c in p] for p in positions]
