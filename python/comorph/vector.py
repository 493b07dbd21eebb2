"""comorph.VectorEnv: num_envs envs stepped by C++ threads with the GIL
released, observations stacked along a first axis of num_envs.

Autoreset: same-step (Gymnasium's AutoresetMode.SAME_STEP). When env i's
episode ends in step(), it is reset at once: the returned obs[i] is the new
episode's first observation, reward[i], terminated[i] and truncated[i] are
the ended episode's, info["final_obs"] holds the last observation (a dict of
stacked arrays, meaningful where info["_final_obs"] is True) and
info["final_info"] its metrics (T, E, D, F, time_s, episode_energy_J,
episode_steps; NaN / 0 elsewhere). The new episode's seed is the next of env
i's seed stream, as a single env's reset() without a seed: so env i steps
exactly like comorph.make(...) reset with seed + i.
"""
import os

import numpy as np

from . import _core
from .env import _core_args, _reset_options, _seed, action_space, observation_space
from .spaces import Box, Dict


def _batched(space, n):
    if isinstance(space, Dict):
        return Dict({k: _batched(s, n) for k, s in space.spaces.items()})
    return Box(np.broadcast_to(space.low, (n,) + space.shape), np.broadcast_to(space.high, (n,) + space.shape),
               (n,) + space.shape, space.dtype)


class VectorEnv:
    metadata = {"autoreset_mode": "SameStep"}

    def __init__(self, num_envs, modules=4, scenario="default", obstacles=None, config_dir=None, threads=None,
                 _env_config=None):
        """threads: C++ threads stepping the envs (default: min(num_envs, CPU cores));
        env i always runs on thread i % threads, so results do not depend on it."""
        if threads is None:
            threads = min(int(num_envs), os.cpu_count() or 1)
        self._core = _core.VectorEnv(num_envs, threads, env_config=_env_config,
                                     **_core_args(modules, scenario, obstacles, config_dir))
        self.num_envs = self._core.num_envs
        self.threads = self._core.threads
        env = _core.Env(env_config=_env_config, **_core_args(modules, scenario, obstacles, config_dir))
        spec = env.spec
        self.single_observation_space = observation_space(spec)
        self.single_action_space = action_space(spec)
        self.observation_space = _batched(self.single_observation_space, self.num_envs)
        self.action_space = _batched(self.single_action_space, self.num_envs)

    def reset(self, *, seed=None, options=None):
        """seed: an int (env i gets seed + i), a list of num_envs ints or Nones, or None.
        options as MultiTaskEnv.reset's, for every env. Returns (obs, info)."""
        if seed is None or isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            seeds = [None] * self.num_envs if seed is None else [_seed(seed) + i for i in range(self.num_envs)]
        elif isinstance(seed, (list, tuple)):
            if len(seed) != self.num_envs:
                raise ValueError(f"reset: {len(seed)} seeds for {self.num_envs} envs")
            seeds = [_seed(s) for s in seed]
        else:
            raise ValueError(f"seed must be an int, a list of {self.num_envs} seeds or None, got {seed!r}")
        modules, height = _reset_options(options)
        return self._core.reset(seeds, modules, height)

    def step(self, actions):
        """actions: float32 (num_envs, 5) in [-1, 1]. Returns (obs, reward, terminated, truncated, info)."""
        return self._core.step(actions)

    def close(self):
        self._core = None

    def __enter__(self):
        return self

    def __exit__(self, *args):
        self.close()
        return False
