"""Steps per second of the Python module against the C++ loop, measured in
one run (docs/python.md, "Speed"):
  1. one env: a Python loop over env.step() vs the same steps in a C++ loop
     (comorph._core.cpp_loop_seconds: the env stepped with no Python in
     between). The binding's overhead is 1 - python / C++ in steps per CPU
     second of the stepping thread (goal <= 15 %); wall-clock rates beside it.
  2. comorph.VectorEnv of 4 envs stepped by 1 and by 2 C++ threads (wall clock).
Rounds alternate between the loops and each loop's best round counts, so a
busy machine shifts both alike; CPU time does not count waiting for a core.

  PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_python.py [steps]
"""
import sys
import time

import numpy as np

import comorph
from comorph import _core

STEPS = int(sys.argv[1]) if len(sys.argv) > 1 else 3000
ROUNDS = 3
MODULES = 4
ACTION = np.array([1.0, 0.0, 0.5, -0.5, 0.5], np.float32)


def python_loop(steps):
    env = comorph.make(modules=MODULES)
    env.reset(seed=1)
    start, cpu = time.perf_counter(), time.thread_time()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(ACTION)
        if terminated or truncated:
            env.reset()
    return time.perf_counter() - start, time.thread_time() - cpu


def cpp_loop(steps):
    return _core.cpp_loop_seconds(comorph.default_config_dir(), MODULES, 1, steps, ACTION.tolist())


def vector_loop(steps, threads, num_envs=4):
    vec = comorph.VectorEnv(num_envs, modules=MODULES, threads=threads)
    vec.reset(seed=1)
    actions = np.tile(ACTION, (num_envs, 1))
    start = time.perf_counter()
    for _ in range(steps // num_envs):
        vec.step(actions)
    return time.perf_counter() - start


def main():
    python_loop(200), cpp_loop(200)  # warm: compiled models, caches
    inf = float("inf")
    wall = {"python": inf, "cpp": inf, 1: inf, 2: inf}
    cpu = {"python": inf, "cpp": inf}
    vec_steps = (STEPS // 4) * 4
    for _ in range(ROUNDS):
        for name, loop in (("cpp", cpp_loop), ("python", python_loop)):
            w, c = loop(STEPS)
            wall[name], cpu[name] = min(wall[name], w), min(cpu[name], c)
        for threads in (1, 2):
            wall[threads] = min(wall[threads], vector_loop(STEPS, threads))
    rate = {k: (vec_steps if k in (1, 2) else STEPS) / v for k, v in wall.items()}
    cpu_rate = {k: STEPS / v for k, v in cpu.items()}
    ratio = cpu_rate["python"] / cpu_rate["cpp"]
    print(f"bench_python: {STEPS} control steps of a {MODULES}-module chain a loop, best of {ROUNDS} rounds")
    print(f"  C++ loop                  {cpu_rate['cpp']:8.0f} steps per CPU s  {rate['cpp']:8.0f} steps/s wall")
    print(f"  Python loop (one env)     {cpu_rate['python']:8.0f} steps per CPU s  {rate['python']:8.0f} steps/s wall")
    print(f"  python / C++ = {ratio:.3f} per CPU s (overhead {100 * (1 - ratio):.1f} %, goal <= 15 %), "
          f"{rate['python'] / rate['cpp']:.3f} wall")
    print(f"  VectorEnv(4), 1 thread    {rate[1]:8.0f} steps/s wall   / C++ loop = {rate[1] / rate['cpp']:.3f}")
    print(f"  VectorEnv(4), 2 threads   {rate[2]:8.0f} steps/s wall   / 1 thread = {rate[2] / rate[1]:.3f}")


if __name__ == "__main__":
    main()
