"""One episode of comorph/MultiTask-v0 with random actions (no torch needed).

  PYTHONPATH=build/python /usr/bin/python3 examples/random_agent.py
"""
import comorph

env = comorph.make("comorph/MultiTask-v0", modules=4)
obs, info = env.reset(seed=1)
print("observation:", {k: (v.shape, str(v.dtype)) for k, v in obs.items()}, "action:", env.action_space)
total = 0.0
while True:
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    total += reward
    if terminated or truncated:
        break
print(f"{info['episode_steps']} steps, return {total:.1f}, ended by {info['termination']}, "
      f"stairs {info['stair_height']} m climbed: {info['stairs_climbed']}, F = {info['F']:.3f}")
