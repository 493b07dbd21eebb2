"""comorph.Configuration: a robot configuration C = {C_a, C_s} (paper Sec.
II-A) as two numpy arrays, checked and read/written by the C++ morphology layer."""
import os

import numpy as np

from . import _core


class Configuration:
    """C_a: int64 (10, 10), 1 where modules i and j are connected.
    C_s: int64 (10, 5), one row per connection (module_i, module_j, face_i,
    face_j, connected); an all-zero row is unused. Modules are 1-based."""

    def __init__(self, C_a=None, C_s=None):
        self.C_a = np.zeros((10, 10), np.int64) if C_a is None else np.array(C_a, dtype=np.int64)
        self.C_s = np.zeros((10, 5), np.int64) if C_s is None else np.array(C_s, dtype=np.int64)
        if self.C_a.shape != (10, 10):
            raise ValueError(f"C_a: shape {self.C_a.shape}, expected (10, 10)")
        if self.C_s.shape != (10, 5):
            raise ValueError(f"C_s: shape {self.C_s.shape}, expected (10, 5)")

    @classmethod
    def chain(cls, modules):
        """The chain of `modules` modules (2..10)."""
        return cls(*_core.chain(modules))

    @classmethod
    def from_yaml(cls, path):
        """Reads a configuration file (`C_a:`/`C_s:` or `modules: N`); errors name the file and the field."""
        return cls(*_core.load_yaml(os.fspath(path)))

    @classmethod
    def from_yaml_string(cls, text, source="<string>"):
        return cls(*_core.from_yaml_text(text, source))

    def to_yaml(self, path=None):
        """The YAML text; also written to `path` when given."""
        text = _core.to_yaml(self.C_a, self.C_s)
        if path is not None:
            with open(path, "w") as f:
                f.write(text)
        return text

    def validate(self):
        """Raises ValueError naming the first fault (as `comorph config validate`); returns self."""
        fault = _core.validate(self.C_a, self.C_s)
        if fault:
            raise ValueError(fault)
        return self

    def is_valid(self):
        return not _core.validate(self.C_a, self.C_s)

    @property
    def modules(self):
        """Number of modules of a valid configuration (ValueError otherwise)."""
        return int(self.validate().C_a.any(axis=1).sum())

    def describe(self):
        return _core.describe(self.C_a, self.C_s)

    def __eq__(self, other):
        return (isinstance(other, Configuration) and np.array_equal(self.C_a, other.C_a)
                and np.array_equal(self.C_s, other.C_s))

    def __repr__(self):
        return f"Configuration({self.describe() if self.is_valid() else 'invalid'})"
