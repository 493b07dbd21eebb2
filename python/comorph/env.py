"""comorph/MultiTask-v0: the paper's multi-task episode (climb the stairs,
cross the obstacle field, reach the target) as a Gymnasium-style env over the
C++ task::MultiTaskEnv."""
import numbers
import os

import numpy as np

from . import _core
from .spaces import Box, Dict

try:
    import gymnasium as _gym
    _EnvBase = _gym.Env
except ImportError:  # the same surface without Gymnasium
    _gym = None

    class _EnvBase:
        metadata = {}
        render_mode = None
        spec = None
        _np_random = None

        @property
        def np_random(self):
            if self._np_random is None:
                self._np_random = np.random.default_rng()
            return self._np_random

        def reset(self, *, seed=None, options=None):
            if seed is not None:
                self._np_random = np.random.default_rng(seed)

        @property
        def unwrapped(self):
            return self

        def __enter__(self):
            return self

        def __exit__(self, *args):
            self.close()
            return False

        def __str__(self):
            return f"<{type(self).__name__}<{ENV_ID}>>"

ENV_ID = "comorph/MultiTask-v0"
TERMINATIONS = tuple(_core.termination_names())  # info["termination"] values; VectorEnv's info["reason"] indexes it
# The scenarios of `comorph eval --scenario`, from the C++ registry (task::kScenarios):
# name -> (obstacles K or None for the scene's default, mixed variant).
SCENARIOS = dict(_core.scenarios())
_OPTIONS = ("modules", "stair_height")


def default_config_dir():
    """The simulator config env makes read: $COMORPH_CONFIG_DIR, else the
    configs/sim of comorph's data files (the one `comorph` and the trainer
    read by default; see _core.resource_dir)."""
    env = os.environ.get("COMORPH_CONFIG_DIR")
    if env:
        return env
    return os.path.join(_core.resource_dir(), "configs", "sim")


def _whole(value, name, allow_none=False):
    if value is None and allow_none:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    return int(value)


def _core_args(modules, scenario, obstacles, config_dir):
    """Checked constructor arguments shared by MultiTaskEnv and VectorEnv."""
    if scenario not in SCENARIOS:
        raise ValueError(f"scenario {scenario!r} is not one of {', '.join(SCENARIOS)}")
    scene_obstacles, mixed = SCENARIOS[scenario]
    obstacles = _whole(obstacles, "obstacles", allow_none=True)
    if obstacles is None:
        obstacles = scene_obstacles
    if config_dir is None:
        config_dir = default_config_dir()
    if not isinstance(config_dir, (str, os.PathLike)):
        raise ValueError(f"config_dir must be a path, got {config_dir!r}")
    return dict(config_dir=os.fspath(config_dir), modules=_whole(modules, "modules"),
                obstacles=-1 if obstacles is None else obstacles, mixed=mixed)


def _reset_options(options):
    if options is None:
        return 0, 0.0
    if not isinstance(options, dict):
        raise ValueError(f"options must be a dict, got {type(options).__name__}")
    unknown = set(options) - set(_OPTIONS)
    if unknown:
        raise ValueError(f"unknown reset option(s) {sorted(unknown)}; known: {', '.join(_OPTIONS)}")
    modules = _whole(options.get("modules", 0), "options['modules']")
    height = options.get("stair_height", 0.0)
    if isinstance(height, bool) or not isinstance(height, numbers.Real):
        raise ValueError(f"options['stair_height'] must be a number of metres, got {height!r}")
    return modules, float(height)


def _seed(seed):
    seed = _whole(seed, "seed", allow_none=True)
    if seed is not None and seed < 0:
        raise ValueError(f"seed must be >= 0, got {seed}")
    return seed


def observation_space(spec):
    """The Dict space of an observation, from the env's declared spec."""
    return Dict({
        "depth": Box(spec["depth_low"], spec["depth_high"], spec["depth_shape"], np.float32),
        "state": Box(-np.inf, np.inf, (spec["state_size"],), np.float32),
        "clearance": Box(spec["depth_low"], spec["depth_high"], (spec["clearance_size"],), np.float32),
    })


def action_space(spec):
    return Box(spec["action_low"], spec["action_high"], (spec["action_size"],), np.float32)


class MultiTaskEnv(_EnvBase):
    """The multi-task episode with a chain of `modules` modules.

    Observation: {"depth": float32 1 x H x W in [0.01, 1] (module 1's depth
    camera), "state": float32 (46,) (task::obs layout: battery, position,
    velocity, previous reward and action, distance sensors, module mask,
    goal bearing and distance, motion mode), "clearance": float32 (C,) (the
    obstacle scan or nearest depth per image column)}. Action: float32 (5,)
    in [-1, 1] (speed, turn, wave amplitudes, phase); the motion mode is the
    ground truth's (stair mode until the chain is on the top, then flat).
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 31}

    def __init__(self, modules=4, scenario="default", obstacles=None, config_dir=None, render_mode=None,
                 _env_config=None):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode {render_mode!r} is not supported (None or 'rgb_array')")
        self.render_mode = render_mode
        self.scenario = scenario
        self._core = _core.Env(env_config=_env_config, **_core_args(modules, scenario, obstacles, config_dir))
        spec = self._core.spec
        self.env_spec = spec
        self.metadata = dict(self.metadata, render_fps=int(round(1.0 / spec["control_period_s"])))
        self.observation_space = observation_space(spec)
        self.action_space = action_space(spec)

    def reset(self, *, seed=None, options=None):
        """New episode: episode `seed` (the scene: stair height, obstacles,
        target, start noise), or, without a seed, the next seed of the
        stream the last seed started. options: "modules" (2..10, this
        episode's chain) and "stair_height" (m; 0 draws it from the seed)."""
        seed = _seed(seed)
        super().reset(seed=seed)
        modules, height = _reset_options(options)
        return self._core.reset(seed, modules, height)

    def step(self, action):
        """(obs, reward R1, terminated, truncated, info). info: termination
        (a name of TERMINATIONS), scene (0 stairs, 1 obstacles, 2 target),
        modules, step, seed, stair_height, stairs_climbed, energy_J (this
        step's joules); at the end also T, E, D, F (Eq. 1), time_s,
        episode_energy_J and episode_steps."""
        return self._core.step(action)

    def reconfigure(self, modules):
        """Sheds tail modules mid-episode (to 2 <= modules < current), as the trainer does."""
        self._core.reconfigure(_whole(modules, "modules"))

    def decision_depth(self):
        """The decision camera's image (1 x h x w), what a run's configuration model sees."""
        return self._core.decision_depth()

    def metrics(self):
        """Eq. 1's metrics of the episode so far (T, E, D, F, time_s, episode_energy_J, episode_steps)."""
        return self._core.metrics()

    @property
    def modules(self):
        return self._core.modules

    def render(self):
        """uint8 480 x 640 x 3 from a camera following the robot (headless EGL)."""
        if self.render_mode != "rgb_array":
            raise RuntimeError("render() needs render_mode='rgb_array' at make()")
        return self._core.render()

    def close(self):
        self._core.close()


def make(env_id=ENV_ID, **kwargs):
    """comorph.make("comorph/MultiTask-v0", modules=4, scenario="default",
    obstacles=None, config_dir=None, render_mode=None)."""
    if env_id != ENV_ID:
        raise ValueError(f"unknown env id {env_id!r}; comorph has {ENV_ID!r}")
    return MultiTaskEnv(**kwargs)
