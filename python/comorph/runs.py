"""Trained run directories (`comorph train`, results/): the configuration
model's choice and the motion model's greedy action, and `comorph eval`'s
evaluation. These link LibTorch (comorph._runs, imported on first use).

Relative paths in a run's config (trainer.classifier_dir: runs/classifier)
are relative to the working directory, as for `comorph eval`."""
import json
import os

import numpy as np

from .env import MultiTaskEnv


def _runs():
    from . import _runs
    return _runs


class Run:
    """A trained run: load_run(path)."""

    def __init__(self, path):
        self._run = _runs().Run(os.fspath(path))
        self.path = self._run.path
        self.hierarchical = self._run.hierarchical

    def make_env(self, modules=10, scenario=None, obstacles=None, render_mode=None):
        """An env with the run's simulator config (configs/sim + its env: overrides),
        the one its networks were trained on."""
        return MultiTaskEnv(modules=modules, scenario=scenario or self._run.scenario, obstacles=obstacles,
                            render_mode=render_mode, _env_config=self._run.env_config())

    def choose_modules(self, image, max_modules=10, scene=0, target_distance_m=None):
        """The configuration model's greedy choice of modules (2..max_modules) for
        its image (env.decision_depth() when the run uses the decision camera,
        else obs["depth"]), the largest allowed chain C_n and the scene label.
        A run trained with trainer.config_target_distance also needs
        info["target_distance_m"]; other runs ignore it."""
        d = -1.0 if target_distance_m is None else float(target_distance_m)
        return self._run.choose_modules(np.asarray(image, np.float32), int(max_modules), int(scene), d)

    def act(self, obs):
        """The motion model's greedy action (float32 (5,)) for an env observation."""
        return self._run.act(obs["depth"], obs["state"], obs["clearance"])


def load_run(path):
    return Run(path)


def evaluate(path, episodes=None, seed=None, scenario="default", workers=2):
    """`comorph eval --run path --episodes N --seed S --scenario X`: greedy
    episodes on the paper's protocol (episode i: seed + i, stair height cycling
    0.04 / 0.06 / 0.08 m). Returns what eval-<scenario>.json holds, as a dict;
    nothing is written. episodes/seed None: the run config's eval section.
    The numbers do not depend on workers (threads)."""
    text = _runs().evaluate(os.fspath(path), 0 if episodes is None else int(episodes),
                            -1 if seed is None else int(seed), scenario, int(workers))
    return json.loads(text)
