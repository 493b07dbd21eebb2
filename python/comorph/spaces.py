"""Observation and action spaces: Gymnasium's when it can be imported, else
two small classes with the same contract (shape, dtype, low, high, seed(),
sample(), contains())."""
import numpy as np

try:
    from gymnasium.spaces import Box, Dict  # noqa: F401
except ImportError:

    class Box:
        """A box in R^n: every element in [low, high], of one dtype."""

        def __init__(self, low, high, shape=None, dtype=np.float32, seed=None):
            self.dtype = np.dtype(dtype)
            if shape is None:
                shape = np.shape(low)
            self.shape = tuple(int(s) for s in shape)
            self.low = np.full(self.shape, low, dtype=self.dtype) if np.isscalar(low) else np.asarray(low, self.dtype)
            self.high = np.full(self.shape, high, dtype=self.dtype) if np.isscalar(high) else np.asarray(high, self.dtype)
            if self.low.shape != self.shape or self.high.shape != self.shape:
                raise ValueError(f"Box: low {self.low.shape} and high {self.high.shape} do not match shape {self.shape}")
            self.seed(seed)

        def seed(self, seed=None):
            self.np_random = np.random.default_rng(seed)
            return [seed]

        def sample(self):
            """Uniform where both bounds are finite, normal where neither is,
            exponential from the finite bound otherwise (Gymnasium's rule)."""
            lo, hi = self.low.astype(np.float64), self.high.astype(np.float64)
            out = np.empty(self.shape)
            both = np.isfinite(lo) & np.isfinite(hi)
            none = ~np.isfinite(lo) & ~np.isfinite(hi)
            low_only = np.isfinite(lo) & ~np.isfinite(hi)
            high_only = ~np.isfinite(lo) & np.isfinite(hi)
            r = self.np_random
            out[both] = r.uniform(lo[both], hi[both])
            out[none] = r.normal(size=none.sum())
            out[low_only] = lo[low_only] + r.exponential(size=low_only.sum())
            out[high_only] = hi[high_only] - r.exponential(size=high_only.sum())
            return np.clip(out, lo, hi).astype(self.dtype)

        def contains(self, x):
            if not isinstance(x, np.ndarray):
                try:
                    x = np.asarray(x, dtype=self.dtype)
                except (ValueError, TypeError):
                    return False
            return bool(np.can_cast(x.dtype, self.dtype) and x.shape == self.shape
                        and np.all(x >= self.low) and np.all(x <= self.high))

        def __contains__(self, x):
            return self.contains(x)

        def __repr__(self):
            return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"

    class Dict:
        """A dictionary of spaces; samples and members are dicts with the same keys."""

        def __init__(self, spaces, seed=None):
            self.spaces = dict(spaces)
            self.shape = None
            self.dtype = None
            self.seed(seed)

        def seed(self, seed=None):
            seeds = np.random.SeedSequence(seed).spawn(len(self.spaces))
            for space, s in zip(self.spaces.values(), seeds):
                space.seed(int(s.generate_state(1)[0]))
            return [seed]

        def sample(self):
            return {k: s.sample() for k, s in self.spaces.items()}

        def contains(self, x):
            return (isinstance(x, dict) and x.keys() == self.spaces.keys()
                    and all(s.contains(x[k]) for k, s in self.spaces.items()))

        def __contains__(self, x):
            return self.contains(x)

        def __getitem__(self, key):
            return self.spaces[key]

        def keys(self):
            return self.spaces.keys()

        def __repr__(self):
            return "Dict(" + ", ".join(f"{k!r}: {s}" for k, s in self.spaces.items()) + ")"
