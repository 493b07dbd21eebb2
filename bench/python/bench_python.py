"""Steps per second of the Python module against the C++ loop, measured in
one run (docs/python.md, "Speed"):
  1. one env: a Python loop over env.step() vs the same steps in a C++ loop
     (comorph._core.cpp_loop_seconds: the env stepped with no Python in
     between); the binding's overhead is 1 - python / cpp (goal <= 15 %);
  2. comorph.VectorEnv of 4 envs stepped by 1 and by 2 C++ threads.
Rounds alternate between the loops and each loop's best round counts, so a
busy machine shifts both alike.

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
    start = time.perf_counter()
    for _ in range(steps):
        _, _, terminated, truncated, _ = env.step(ACTION)
        if terminated or truncated:
            env.reset()
    return time.perf_counter() - start


def cpp_loop(steps):
    return _core.cpp_loop_seconds(comorph.default_config_dir(), MODULES, 1, steps, ACTION.tolist())


def vector_loop(steps, threads, num_envs=4):
    vec = comorph.VectorEnv(num_envs, modules=MODULES, threads=threads)
    vec.reset(seed=1)
    actions = np.tile(ACTION, (num_envs, 1))
    start = time.perf_counter()
    for _ in range(steps // num_envs):
        vec.step(actions)
    return time.perf_counter() - start, (steps // num_envs) * num_envs


def main():
    python_loop(200), cpp_loop(200)  # warm: compiled models, caches
    best = {"python": float("inf"), "cpp": float("inf"), "vec1": float("inf"), "vec2": float("inf")}
    vec_steps = STEPS
    for _ in range(ROUNDS):
        best["cpp"] = min(best["cpp"], cpp_loop(STEPS))
        best["python"] = min(best["python"], python_loop(STEPS))
        for threads in (1, 2):
            seconds, vec_steps = vector_loop(STEPS, threads)
            best[f"vec{threads}"] = min(best[f"vec{threads}"], seconds)
    rate = {k: (vec_steps if k.startswith("vec") else STEPS) / v for k, v in best.items()}
    print(f"bench_python: {STEPS} control steps of a {MODULES}-module chain a loop, best of {ROUNDS} rounds")
    print(f"  C++ loop                  {rate['cpp']:9.0f} steps/s")
    print(f"  Python loop (one env)     {rate['python']:9.0f} steps/s   python / C++ = {rate['python'] / rate['cpp']:.3f}"
          f"  (overhead {100 * (1 - rate['python'] / rate['cpp']):.1f} %, goal <= 15 %)")
    print(f"  VectorEnv(4), 1 thread    {rate['vec1']:9.0f} steps/s   / C++ loop = {rate['vec1'] / rate['cpp']:.3f}")
    print(f"  VectorEnv(4), 2 threads   {rate['vec2']:9.0f} steps/s   / 1 thread = {rate['vec2'] / rate['vec1']:.3f}")


if __name__ == "__main__":
    main()
