"""snh.material, Material.psi/pk1/hessian/eigensystem/defined, snh.svd, snh.stability_table: against the
command line (snh material --json, the same C++), analytic values and finite differences; batches against
single calls; bad input."""
import math

import numpy as np
import pytest

import snh
from conftest import cli_error, snh_cli, snh_json

NAMES = snh.material_names()

# A general F with J > 0, and a reflected diagonal one (docs/python.md's example).
F_GENERAL = np.array([[1.1, 0.2, -0.1], [0.05, 0.9, 0.3], [-0.2, 0.1, 1.2]])
F_INVERTED = np.diag([1.2, 0.9, -0.5])


def vec_text(F):
    """vec(F), column by column, as snh material --F takes it."""
    return " ".join(repr(float(v)) for v in np.asarray(F).T.reshape(-1))


def test_names_are_the_command_lines():
    assert len(NAMES) == 11 and "stable_neo_hookean" in NAMES
    listed = [line.split()[0] for line in snh_cli("material", "--list")[1].splitlines()]
    assert NAMES == listed


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("F", [F_GENERAL, F_INVERTED], ids=["general", "inverted"])
def test_values_agree_with_snh_material(name, F):
    m = snh.material(name, mu=2.0, lam=30.0)
    j = snh_json("material", name, "--mu", 2, "--lambda", 30, "--F", vec_text(F), "--projection", "clamp")
    assert m.mu == j["mu"] and m.lam == j["lambda"] and m.formula == j["formula"]
    assert bool(m.defined(F)) == j["defined"]
    if not j["defined"]:
        assert m.psi(F) == math.inf
        assert not m.pk1(F).any() and not m.hessian(F).any()
        with pytest.raises(ValueError, match=f"{name} is undefined for J <= 0"):
            m.eigensystem(F)
        return
    np.testing.assert_allclose(m.psi(F), j["psi"], rtol=1e-14)
    np.testing.assert_allclose(m.pk1(F), np.array(j["P"]), rtol=1e-13, atol=1e-13)
    es = m.eigensystem(F, projection="clamp")
    assert es["labels"] == [e["label"] for e in j["eigenvalues"]]
    np.testing.assert_allclose(es["values"], [e["value"] for e in j["eigenvalues"]], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(es["projected"], [e["projected"] for e in j["eigenvalues"]], rtol=1e-13, atol=1e-12)


def test_reparametrize_and_youngs_agree_with_snh_material():
    for name in ["stable_neo_hookean", "neo_hookean", "stvk"]:
        m = snh.material(name, mu=1.0, lam=10.0, reparametrize=True)
        j = snh_json("material", name, "--reparametrize", "--stretch", 1, 1, 1)
        assert (m.mu, m.lam) == (j["mu"], j["lambda"]) and m.given == (1.0, 10.0)
    m = snh.material("stable_neo_hookean", youngs=1000.0, poisson=0.45)
    j = snh_json("material", "stable_neo_hookean", "--youngs", 1000, "--poisson", 0.45, "--stretch", 1, 1, 1)
    assert (m.mu, m.lam) == (j["mu"], j["lambda"])
    np.testing.assert_allclose([m.youngs, m.nu], [1000.0, 0.45], rtol=1e-12)


def test_rest_state_and_known_values():
    # Stable Neo-Hookean: psi(I) = 0 and P(I) = 0 (its alpha makes the rest state stress-free).
    m = snh.material("stable_neo_hookean", mu=1.0, lam=10.0)
    assert abs(m.psi(np.eye(3))) < 1e-15 and np.abs(m.pk1(np.eye(3))).max() < 1e-14
    # docs/python.md's example: psi at diag(1.2, 0.9, -0.5) is 13.148.
    assert m.psi(F_INVERTED) == pytest.approx(13.148, rel=1e-12)
    # Linear elasticity: psi = mu |eps|^2 + lam/2 tr(eps)^2 with eps = sym(F) - I.
    lin = snh.material("linear", mu=2.0, lam=3.0)
    eps = 0.5 * (F_GENERAL + F_GENERAL.T) - np.eye(3)
    assert lin.psi(F_GENERAL) == pytest.approx(2.0 * (eps * eps).sum() + 1.5 * np.trace(eps) ** 2, rel=1e-13)


@pytest.mark.parametrize("name", NAMES)
def test_derivatives_by_finite_differences(name):
    m = snh.material(name)
    F = F_GENERAL
    P, H = m.pk1(F), m.hessian(F)
    h = 1e-6
    for i in range(3):
        for j in range(3):
            E = np.zeros((3, 3))
            E[i, j] = h
            dpsi = (m.psi(F + E) - m.psi(F - E)) / (2 * h)
            assert dpsi == pytest.approx(P[i, j], rel=1e-6, abs=1e-7)
            # H over vec(F) column by column: column i + 3 j is dP/dF[i, j].
            dP = (m.pk1(F + E) - m.pk1(F - E)) / (2 * h)
            np.testing.assert_allclose(H[:, i + 3 * j], dP.T.reshape(-1), rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("name", NAMES)
def test_eigensystem_rebuilds_the_hessians(name):
    m = snh.material(name)
    for F in [F_GENERAL] + ([F_INVERTED] if m.inversion_safe else []):
        es = m.eigensystem(F)
        Q, v = es["vectors"], es["values"]
        scale = np.abs(v).max()
        np.testing.assert_allclose(Q.T @ Q, np.eye(9), atol=1e-12)
        np.testing.assert_allclose(Q @ np.diag(v) @ Q.T, m.hessian(F, projection="none"), atol=1e-10 * scale)
        np.testing.assert_allclose(Q @ np.diag(np.maximum(v, 0)) @ Q.T, m.hessian(F, projection="clamp"), atol=1e-10 * scale)
        np.testing.assert_allclose(Q @ np.diag(np.abs(v)) @ Q.T, m.hessian(F, projection="abs"), atol=1e-10 * scale)


def random_batch(n, seed):
    rng = np.random.default_rng(seed)
    F = np.eye(3) + 0.3 * rng.standard_normal((n, 3, 3))
    F[::7, :, 2] *= -1  # some reflected
    return F


@pytest.mark.parametrize("name", NAMES)
def test_batch_equals_single_calls(name):
    m = snh.material(name)
    F = random_batch(200, 1)  # over the parallel threshold
    psi, P, H = m.psi(F), m.pk1(F), m.hessian(F, projection="clamp")
    assert psi.shape == (200,) and P.shape == (200, 3, 3) and H.shape == (200, 9, 9)
    defined = m.defined(F)
    assert defined.dtype == bool and defined.shape == (200,)
    for k in range(0, 200, 13):
        assert psi[k] == m.psi(F[k]) and defined[k] == m.defined(F[k])
        assert np.array_equal(P[k], m.pk1(F[k])) and np.array_equal(H[k], m.hessian(F[k], projection="clamp"))
    ok = F[defined]
    es = m.eigensystem(ok)
    for k in range(0, len(ok), 17):
        one = m.eigensystem(ok[k])
        assert np.array_equal(es["values"][k], one["values"]) and np.array_equal(es["vectors"][k], one["vectors"])


def test_svd():
    F = random_batch(100, 2)
    U, s, V = snh.svd(F)
    np.testing.assert_allclose(U @ (s[:, :, None] * np.swapaxes(V, 1, 2)), F, atol=1e-13)
    np.testing.assert_allclose(np.linalg.det(U), 1.0, atol=1e-13)
    np.testing.assert_allclose(np.linalg.det(V), 1.0, atol=1e-13)
    assert (np.abs(s[:, 0]) >= np.abs(s[:, 1])).all() and (np.abs(s[:, 1]) >= np.abs(s[:, 2])).all()
    assert (np.sign(s[:, 2]) == np.sign(np.linalg.det(F))).all()
    U1, s1, V1 = snh.svd(F[3])
    assert np.array_equal(U1, U[3]) and np.array_equal(s1, s[3]) and np.array_equal(V1, V[3])
    # The sigma of snh material's JSON.
    j = snh_json("material", "stable_neo_hookean", "--F", vec_text(F_INVERTED))
    assert np.array_equal(snh.svd(F_INVERTED)[1], j["sigma"])


def test_stability_table_agrees_with_snh_material():
    rows = snh.stability_table(samples=20, seed=3)
    j = snh_json("material", "--stability", "--samples", 20, "--seed", 3)
    assert rows == j["rows"]
    assert [r["energy"] for r in rows] == NAMES


def test_integer_input_is_taken_as_float():
    m = snh.material("stable_neo_hookean")
    assert m.psi(np.eye(3, dtype=np.int64)) == m.psi(np.eye(3))
    assert m.psi([[1, 0, 0], [0, 1, 0], [0, 0, 1]]) == m.psi(np.eye(3))


@pytest.mark.parametrize("F, message", [
    (np.eye(4), r"F must have shape \(3, 3\) or \(n, 3, 3\), got \(4, 4\)"),
    (np.zeros((2, 3)), r"F must have shape \(3, 3\) or \(n, 3, 3\), got \(2, 3\)"),
    (np.zeros(9), r"F must have shape \(3, 3\) or \(n, 3, 3\), got \(9,\)"),
    (np.eye(3, dtype=complex), "F must hold real numbers \\(float or integer\\), got dtype complex128"),
    (np.eye(3, dtype=bool), "F must hold real numbers \\(float or integer\\), got dtype bool"),
    ("abc", "F must hold real numbers"),
    (np.array([[1.0, math.nan, 0], [0, 1, 0], [0, 0, 1]]), r"F entry \(0, 1\) is not a finite number: nan"),
    (np.array([np.eye(3), np.diag([1.0, math.inf, 1.0])]), r"F entry \(1, 1, 1\) is not a finite number: inf"),
    (np.diag([1e300, 1.0, 1.0]), r"F entry \(0, 0\) = 1e\+300 is outside the supported range \(0 or \|f\| in \[1e-20, 1e\+20\]\)"),
])
def test_bad_F(F, message):
    m = snh.material("stable_neo_hookean")
    for call in (m.psi, m.pk1, m.hessian, m.eigensystem, m.defined):
        with pytest.raises(ValueError, match=message):
            call(F)


def test_bad_parameters_give_the_command_lines_messages():
    cases = [
        (dict(name="stable_neohookean"), ["stable_neohookean"]),
        (dict(name="stable_neo_hookean", mu=0.0), ["stable_neo_hookean", "--mu", "0"]),
        (dict(name="arap", reparametrize=True), ["arap", "--reparametrize"]),
        (dict(name="stable_neo_hookean", mu=1e300), ["stable_neo_hookean", "--mu", "1e300"]),
        (dict(name="stable_neo_hookean", lam=-1e-300), ["stable_neo_hookean", "--lambda=-1e-300"]),
        (dict(name="stable_neo_hookean", youngs=1.0, poisson=0.5), ["stable_neo_hookean", "--youngs", "1", "--poisson", "0.5"]),
        (dict(name="stable_neo_hookean", youngs=-1.0, poisson=0.3), ["stable_neo_hookean", "--youngs", "-1", "--poisson", "0.3"]),
    ]
    for kwargs, args in cases:
        expected = cli_error("material", *args, "--stretch", 1, 1, 1)
        with pytest.raises(ValueError) as e:
            snh.material(**kwargs)
        assert str(e.value) == expected
    with pytest.raises(ValueError, match="lambda must be a finite number, got nan"):
        snh.material("stable_neo_hookean", lam=math.nan)
    with pytest.raises(ValueError, match="youngs and poisson go together"):
        snh.material("stable_neo_hookean", youngs=1.0)
    with pytest.raises(ValueError, match="give mu and lam, or youngs and poisson, not both"):
        snh.material("stable_neo_hookean", mu=1.0, youngs=1.0, poisson=0.3)
    m = snh.material("stable_neo_hookean")
    with pytest.raises(ValueError, match="projection must be none, clamp or abs, got 'bogus'"):
        m.hessian(np.eye(3), projection="bogus")
    with pytest.raises(ValueError, match="samples must be from 1 to 1000000, got 0"):
        snh.stability_table(samples=0)
