"""snh.box, snh.read_mesh, snh.write_mesh: shapes, round trips through every writable format, and the readers'
one-line errors as ValueError (the same lines snh info prints for the malformed meshes of tests/data)."""
import numpy as np
import pytest

import snh
from conftest import SOURCE


def test_box():
    V, C, kind = snh.box("tet4", 2)
    assert kind == "tet4" and V.shape == (27, 3) and C.shape == (48, 4) and C.dtype == np.int32
    # Lattice index i + j (res+1) + k (res+1)^2 at (-1, -1, -1) + (2/res)(i, j, k).
    np.testing.assert_array_equal(V[1 + 3 * 2], [0.0, 1.0, -1.0])
    V, C, kind = snh.box("hex", 3)
    assert kind == "hex8" and V.shape == (64, 3) and C.shape == (27, 8)
    # Hex corners: c1 = c0 + x, c2 = c0 + y, c4 = c0 + z.
    c = V[C[0]]
    np.testing.assert_allclose(c[1] - c[0], [2 / 3, 0, 0])
    np.testing.assert_allclose(c[2] - c[0], [0, 2 / 3, 0])
    np.testing.assert_allclose(c[4] - c[0], [0, 0, 2 / 3])
    assert not np.array_equal(snh.box("tet4", 2, "mirrored")[1], snh.box("tet4", 2)[1])


@pytest.mark.parametrize("args, message", [
    (("prism", 2), "element must be tet4 or hex8, got 'prism'"),
    (("tet4", 0), "resolution must be an integer from 1 to 400, got 0"),
    (("tet4", 2, "diagonal"), "tet_split must be paper or mirrored, got 'diagonal'"),
])
def test_box_errors(args, message):
    with pytest.raises(ValueError, match=message):
        snh.box(*args)


@pytest.mark.parametrize("element", ["tet4", "hex8"])
@pytest.mark.parametrize("extension", ["msh", "vtu", "mesh"])
def test_write_read_round_trip(tmp_path, element, extension):
    V, C, kind = snh.box(element, 2)
    V = V + 0.01 * np.sin(7 * V)  # coordinates that need every digit
    path = tmp_path / f"box.{extension}"
    snh.write_mesh(path, V, C)
    V2, C2, kind2 = snh.read_mesh(str(path))
    assert kind2 == kind
    np.testing.assert_array_equal(C2, C)
    if extension == "vtu":  # binary: every double as it was
        np.testing.assert_array_equal(V2, V)
    else:
        np.testing.assert_allclose(V2, V, rtol=1e-15, atol=1e-15)


def test_write_mesh_errors(tmp_path):
    V, C, _ = snh.box("tet4", 1)
    bad = C.copy()
    bad[2, 3] = 8
    with pytest.raises(ValueError, match=r"cells\[2, 3\] = 8 is not a vertex index \(0 to 7\)"):
        snh.write_mesh(tmp_path / "a.msh", V, bad)
    with pytest.raises(ValueError, match=r"cells must have shape \(m, 4\) \(tets\) or \(m, 8\) \(hexes\), got \(6, 5\)"):
        snh.write_mesh(tmp_path / "a.msh", V, np.zeros((6, 5), dtype=int))
    with pytest.raises(ValueError, match="cells must hold integer vertex indices, got dtype float64"):
        snh.write_mesh(tmp_path / "a.msh", V, C.astype(float))
    Vn = V.copy()
    Vn[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"vertices entry \(3, 1\) is not a finite number: nan"):
        snh.write_mesh(tmp_path / "a.msh", Vn, C)
    with pytest.raises(ValueError, match="obj"):
        snh.write_mesh(tmp_path / "a.obj", V, C)
    assert not list(tmp_path.iterdir())


MALFORMED = sorted((SOURCE / "tests/data/malformed").glob("*.expected"))


@pytest.mark.parametrize("expected", MALFORMED, ids=[p.stem for p in MALFORMED])
def test_malformed_meshes_raise_the_readers_line(expected):
    mesh = expected.with_suffix("")
    with pytest.raises(ValueError) as e:
        snh.read_mesh(mesh)
    message = str(e.value)
    assert "\n" not in message and str(mesh) in message and expected.read_text().strip() in message


def test_missing_file():
    with pytest.raises(ValueError, match="no_such_file.msh"):
        snh.read_mesh("no_such_file.msh")
