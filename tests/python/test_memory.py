"""Memory stays flat over 100 k control steps through the Python module
(observations, info dicts, autoresets). To keep the wall time modest the
config's control period is one physics step (2 ms) instead of 16: the
binding's work per step is the same, the physics 16 times less."""
import re
import shutil

import numpy as np

import comorph
from conftest import SIM_CONFIG


def rss_mb():
    with open("/proc/self/status") as f:
        return int(re.search(r"VmRSS:\s+(\d+) kB", f.read()).group(1)) / 1024


def fast_config(tmp_path):
    out = tmp_path / "sim"
    shutil.copytree(SIM_CONFIG, out)
    robot = (out / "robot.yaml").read_text()
    robot, n = re.subn(r"^control_period:.*$", "control_period: 0.002", robot, flags=re.M)
    assert n == 1
    (out / "robot.yaml").write_text(robot)
    task = (out / "task.yaml").read_text()
    task, n = re.subn(r"^max_steps:.*$", "max_steps: 5000", task, flags=re.M)
    assert n == 1
    (out / "task.yaml").write_text(task)
    return out


def test_memory_is_flat_over_100k_steps(tmp_path):
    config = fast_config(tmp_path)
    env = comorph.make(modules=3, config_dir=config)
    vec = comorph.VectorEnv(2, modules=3, config_dir=config, threads=2)
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, (1000, 5)).astype(np.float32)
    env.reset(seed=1)
    vec.reset(seed=1)

    def run(steps):
        episodes = 0
        for t in range(steps):
            obs, reward, terminated, truncated, info = env.step(acts[t % 1000])
            if terminated or truncated:
                env.reset()
                episodes += 1
            if t % 10 == 0:
                vec.step(acts[[t % 1000, (t + 1) % 1000]])
        return episodes

    run(5000)  # warm: every chain's model, numpy's caches
    before = rss_mb()
    episodes = run(100000)
    growth = rss_mb() - before
    print(f"RSS {before:.1f} MB, growth {growth:.2f} MB over 100k steps ({episodes} episodes)")
    assert episodes >= 15  # resets happened along the way (5000-step cap)
    assert growth < 3.0  # a leak of one observation a step would be ~130 MB
