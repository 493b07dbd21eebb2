"""comorph from Python: the multi-task env of a reconfigurable modular robot
(MuJoCo, C++), a batched env stepping in C++ threads, robot configurations and
trained runs, in Gymnasium's shape (docs/python.md).

    import comorph
    env = comorph.make("comorph/MultiTask-v0", modules=4)
    obs, info = env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

Gymnasium is optional: when it can be imported the env is registered with it
(gymnasium.make("comorph/MultiTask-v0")) and the spaces are Gymnasium's.
"""
from .spaces import Box, Dict
from .env import ENV_ID, SCENARIOS, TERMINATIONS, MultiTaskEnv, default_config_dir, make
from .vector import VectorEnv
from .configuration import Configuration
from .runs import Run, evaluate, load_run

__all__ = ["Box", "Dict", "ENV_ID", "SCENARIOS", "TERMINATIONS", "MultiTaskEnv", "default_config_dir", "make",
           "VectorEnv", "Configuration", "Run", "evaluate", "load_run"]


def _register_gymnasium():
    try:
        import gymnasium
    except ImportError:
        return
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point="comorph.env:MultiTaskEnv")


_register_gymnasium()
