"""comorph.Configuration: C_a and C_s as numpy arrays, chain(n), YAML both
ways (the `comorph config` format), validate() raising ValueError naming the fault."""
import subprocess

import numpy as np
import pytest

import comorph
from conftest import tool


def test_chain_has_the_papers_matrices():
    c = comorph.Configuration.chain(4)
    assert c.C_a.shape == (10, 10) and c.C_s.shape == (10, 5) and c.C_a.dtype == np.int64
    expected = np.zeros((10, 10), np.int64)
    for i in range(3):
        expected[i, i + 1] = expected[i + 1, i] = 1
    np.testing.assert_array_equal(c.C_a, expected)
    np.testing.assert_array_equal(c.C_s[:3], [[1, 2, 2, 1, 1], [2, 3, 2, 1, 1], [3, 4, 2, 1, 1]])
    assert not c.C_s[3:].any()
    assert c.modules == 4 and c.describe() == "chain of 4 modules: 1-2-3-4"
    assert c.validate() is c


def test_yaml_round_trip_and_the_cli_format(tmp_path):
    c = comorph.Configuration.chain(6)
    path = tmp_path / "robot.yaml"
    c.to_yaml(path)
    assert comorph.Configuration.from_yaml(path) == c
    assert comorph.Configuration.from_yaml_string("modules: 6\n") == c
    cli = subprocess.run([tool("COMORPH_EXE"), "config", "chain", "--modules", "6"], capture_output=True, text=True,
                         check=True).stdout
    assert comorph.Configuration.from_yaml_string(cli) == c
    assert cli == c.to_yaml()


@pytest.mark.parametrize("edit,fault", [
    (lambda c: c.C_a.__setitem__((0, 5), 1), "not symmetric"),
    (lambda c: c.C_a.__setitem__((2, 2), 1), "self"),
    (lambda c: c.C_s.__setitem__((0, 2), 3), "face"),
])
def test_validate_names_the_fault(edit, fault):
    c = comorph.Configuration.chain(4)
    edit(c)
    assert not c.is_valid()
    with pytest.raises(ValueError, match=fault):
        c.validate()


def test_bad_input_names_the_field(tmp_path):
    with pytest.raises(ValueError, match=r"C_a: shape \(3, 3\)"):
        comorph.Configuration(np.zeros((3, 3)), np.zeros((10, 5)))
    with pytest.raises(ValueError, match="modules must be in 2..10|2..10"):
        comorph.Configuration.chain(11)
    bad = tmp_path / "bad.yaml"
    bad.write_text("C_a: [[0, 1]]\n")
    with pytest.raises(RuntimeError, match="bad.yaml"):
        comorph.Configuration.from_yaml(bad)
    c = comorph.Configuration.chain(3)
    c.C_a = c.C_a.astype(float)
    c.C_a[0, 1] = 0.5
    with pytest.raises(ValueError, match=r"C_a\[0, 1\] = 0.5.* not a whole number"):
        c.validate()
