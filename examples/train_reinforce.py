"""Trains a small Gaussian policy (PyTorch, Debian's python3-torch) with
REINFORCE on comorph/MultiTask-v0: 8 envs of comorph.VectorEnv stepped in C++
threads, 100-step episodes on flat ground before the stairs, reward R1
(progress towards the goal and heading). Within a minute the policy learns
to drive towards the stairs: the mean return climbs from about 15 to 50.

  PYTHONPATH=build/python /usr/bin/python3 examples/train_reinforce.py [--iterations 30] [--check]

--check exits with status 1 unless the last iterations' return beats the first ones'.
"""
import argparse

import numpy as np
import torch

import comorph

parser = argparse.ArgumentParser()
parser.add_argument("--iterations", type=int, default=30)
parser.add_argument("--envs", type=int, default=8)
parser.add_argument("--horizon", type=int, default=100)
parser.add_argument("--seed", type=int, default=0)
parser.add_argument("--check", action="store_true")
args = parser.parse_args()

torch.manual_seed(args.seed)
vec = comorph.VectorEnv(args.envs, modules=3)
space = vec.single_observation_space
inputs = space["state"].shape[0] + space["clearance"].shape[0]
actions = vec.single_action_space.shape[0]
policy = torch.nn.Sequential(torch.nn.Linear(inputs, 64), torch.nn.Tanh(), torch.nn.Linear(64, actions))
log_std = torch.nn.Parameter(torch.full((actions,), -0.5))
optimizer = torch.optim.Adam(list(policy.parameters()) + [log_std], lr=3e-3)


def features(obs):
    state = obs["state"].copy()
    state[:, 1:4] *= 0.2   # positions (m) to about [-1, 1]
    state[:, 44] *= 0.2    # goal distance (m)
    return torch.from_numpy(np.concatenate([state, obs["clearance"]], axis=1))


returns_seen = []
for iteration in range(args.iterations):
    obs, _ = vec.reset(seed=args.seed * 100000 + iteration * args.envs)
    log_probs, rewards, alive = [], [], np.ones(args.envs, bool)
    masks = []
    for t in range(args.horizon):
        dist = torch.distributions.Normal(policy(features(obs)), log_std.exp())
        action = dist.sample()
        log_probs.append(dist.log_prob(action).sum(-1))
        obs, reward, terminated, truncated, _ = vec.step(action.clamp(-1, 1).numpy().astype(np.float32))
        rewards.append(np.where(alive, reward, 0.0))
        masks.append(alive.copy())
        alive &= ~(terminated | truncated)  # an ended episode's autoreset steps do not count
    rewards = np.array(rewards)             # (horizon, envs)
    togo = np.flip(np.cumsum(np.flip(rewards, 0), 0), 0).copy()
    advantage = torch.from_numpy(togo - togo.mean(axis=1, keepdims=True)).float()
    mask = torch.from_numpy(np.array(masks)).float()
    loss = -(torch.stack(log_probs) * advantage * mask).sum() / mask.sum()
    optimizer.zero_grad()
    loss.backward()
    optimizer.step()
    episode_return = rewards.sum(0).mean()
    returns_seen.append(episode_return)
    print(f"iteration {iteration:3d}  mean return {episode_return:7.2f}  action std {log_std.exp().mean():.2f}")

k = max(1, len(returns_seen) // 5)
first, last = np.mean(returns_seen[:k]), np.mean(returns_seen[-k:])
print(f"mean return of the first {k} iterations {first:.2f}, of the last {k} {last:.2f}")
if args.check and not last > first + 5:
    raise SystemExit("the policy did not improve")
