"""examples/python/compare_energies.py runs: its table agrees with single psi calls, and it draws its plot
where matplotlib is installed."""
import importlib.util
import subprocess
import sys

import numpy as np
import pytest

import snh
from conftest import SOURCE

SCRIPT = SOURCE / "examples/python/compare_energies.py"


def test_compare_energies_text():
    r = subprocess.run([sys.executable, str(SCRIPT), "--text"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    rows = {line.split()[0]: line.split()[1:] for line in r.stdout.splitlines()[2:]}
    assert list(rows) == snh.material_names()
    for name, (at01, at1, _) in rows.items():
        m = snh.material(name)
        assert float(at01) == pytest.approx(m.psi(0.1 * np.eye(3)), rel=1e-5)
        assert float(at1) == pytest.approx(m.psi(np.eye(3)), rel=1e-5, abs=1e-6)
    # Stable Neo-Hookean rests at s = 1; neo_hookean blows up as s -> 0.
    assert float(rows["stable_neo_hookean"][2]) == pytest.approx(1.0, abs=0.02)
    assert float(rows["neo_hookean"][0]) > float(rows["stable_neo_hookean"][0])


def test_compare_energies_plot(tmp_path):
    if importlib.util.find_spec("matplotlib") is None:
        pytest.skip("matplotlib is not installed (the script prints its table instead)")
    out = tmp_path / "psi.png"
    r = subprocess.run([sys.executable, str(SCRIPT), "--out", str(out)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
