"""snh.fibre, snh.active_strain, snh.muscle: finite differences, the closed-form eigensystem against numpy,
the active strain's closed form, the composition a simulation's muscle cell uses, bad input, and a scene
with a muscle run from Python."""
import json

import numpy as np
import pytest

import snh

F_GENERAL = np.array([[1.1, 0.2, -0.1], [0.05, 0.9, 0.3], [-0.2, 0.1, 1.2]])
F_INVERTED = np.diag([1.2, 0.9, -0.5]) @ np.array([[1, 0.1, 0], [0, 1, 0.2], [0.1, 0, 1]])
A = np.array([1.0, 2.0, -0.5])


def fd_gradient(f, F, h=1e-6):
    """dF/dF by central differences, 3x3."""
    G = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            E = np.zeros((3, 3))
            E[i, j] = h
            G[i, j] = (f(F + E) - f(F - E)) / (2 * h)
    return G


def fd_hessian(pk1, F, h=1e-6):
    """dP/dF by central differences over vec(F) column by column (index i + 3 j)."""
    H = np.zeros((9, 9))
    for j in range(3):
        for i in range(3):
            E = np.zeros((3, 3))
            E[i, j] = h
            H[:, i + 3 * j] = ((pk1(F + E) - pk1(F - E)) / (2 * h)).T.reshape(-1)
    return H


@pytest.mark.parametrize("model", ["signed_arap", "quadratic"])
@pytest.mark.parametrize("F", [F_GENERAL, F_INVERTED], ids=["general", "inverted"])
def test_fibre_derivatives_and_eigensystem(model, F):
    f = snh.fibre(A, model=model, stiffness=3.0)
    assert f.model == model and f.stiffness == 3.0
    assert np.allclose(f.direction, A / np.linalg.norm(A))
    assert np.allclose(f.pk1(F), fd_gradient(f.psi, F), atol=1e-6)
    H = f.hessian(F)
    assert np.allclose(H, fd_hessian(f.pk1, F), atol=1e-5)
    es = f.eigensystem(F, projection="none")
    assert np.allclose(np.sort(es["values"]), np.linalg.eigvalsh(H), atol=1e-9)
    Q = es["vectors"]
    assert np.allclose(Q @ np.diag(es["values"]) @ Q.T, H, atol=1e-9)
    assert np.all(np.linalg.eigvalsh(f.hessian(F, projection="clamp")) > -1e-9)
    # A batch is the single calls stacked.
    batch = np.stack([F, F_GENERAL])
    assert np.allclose(f.psi(batch), [f.psi(F), f.psi(F_GENERAL)])


def test_active_strain_closed_form():
    s = snh.active_strain([0, 0, 2], 0.3)
    assert s.alpha == 0.3
    assert np.allclose(s.deformation, np.diag([1 / np.sqrt(0.7), 1 / np.sqrt(0.7), 0.7]))
    assert np.isclose(np.linalg.det(s.deformation), 1.0)
    assert np.allclose(s.inverse @ s.deformation, np.eye(3))


def test_muscle_is_the_material_and_fibre_on_the_elastic_part():
    mat = snh.material("stable_neo_hookean", youngs=1e4, poisson=0.45)
    fib = snh.fibre(A, stiffness=2e3)
    m = snh.muscle(mat, fib, alpha=0.2)
    Ainv = snh.active_strain(A, 0.2).inverse
    for F in (F_GENERAL, F_INVERTED):
        Fe = F @ Ainv
        assert np.isclose(m.psi(F), mat.psi(Fe) + fib.psi(Fe))
        assert np.allclose(m.pk1(F), fd_gradient(m.psi, F), rtol=1e-6, atol=1e-3)
        assert np.allclose(m.hessian(F), fd_hessian(m.pk1, F), rtol=1e-5, atol=1e-2)
        assert np.all(np.linalg.eigvalsh(m.hessian(F, projection="clamp")) > -1e-6 * np.abs(m.hessian(F)).max())
    # Nothing held, a muscle rests at its active shape, turned any way: no stress, no energy.
    R = np.linalg.qr(F_GENERAL)[0]
    R *= np.sign(np.linalg.det(R))
    Fa = snh.active_strain(A, 0.2).deformation
    assert np.allclose(m.pk1(R @ Fa), 0, atol=1e-8)
    assert abs(m.psi(R @ Fa)) < 1e-9
    assert abs(snh.muscle(mat, fib).psi(np.eye(3))) < 1e-12 and snh.muscle(mat, fib).alpha == 0


def test_bad_input():
    with pytest.raises(ValueError, match="direction: a fibre direction must not be zero"):
        snh.fibre([0, 0, 0])
    with pytest.raises(ValueError, match="model: expected signed_arap or quadratic, got 'hill'"):
        snh.fibre([1, 0, 0], model="hill")
    with pytest.raises(ValueError, match="stiffness: must be finite and >= 0"):
        snh.fibre([1, 0, 0], stiffness=-1)
    with pytest.raises(ValueError, match=r"must be in \[0, 1\)"):
        snh.active_strain([1, 0, 0], 1.0)
    with pytest.raises(ValueError, match=r"must be in \[0, 1\)"):
        snh.muscle(snh.material("stable_neo_hookean"), snh.fibre([1, 0, 0]), alpha=float("nan"))
    with pytest.raises(TypeError, match="material must be an snh.Material"):
        snh.muscle("stable_neo_hookean", snh.fibre([1, 0, 0]))


def test_a_scene_with_a_muscle(tmp_path):
    scene = {"mesh": {"box": {"min": [0, 0, 0], "max": [4, 1, 1], "res": 4}}, "material": {"youngs": 1000, "poisson": 0.45},
             "integrator": "quasi_static", "end_time": 1, "frames": 2,
             "pins": [{"region": {"min": [-0.1, -1, -1], "max": [0.1, 2, 2]}}],
             "muscles": [{"name": "belly", "region": {"min": [-1, -1, -1], "max": [5, 2, 2]}, "fibre": [1, 0, 0],
                          "contraction": 0.3, "activation": [{"time": 0, "value": 0}, {"time": 1, "value": 1}]}]}
    r = snh.run_scene(scene, out=tmp_path / "m", quiet=True, report=False)
    assert r["all_converged"]
    muscles = json.loads((tmp_path / "m" / "muscles.json").read_text())
    assert muscles["regions"][0]["activation"] == [0.0, 0.5, 1.0]
    x = np.array([[float(v) for v in line.split()[1:]] for line in (tmp_path / "m" / "002.obj").read_text().splitlines()
                  if line.startswith("v ")])
    assert 2.7 < x[:, 0].max() < 3.0, "the bar shortens towards 4 (1 - 0.3)"
