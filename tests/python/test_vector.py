"""comorph.VectorEnv equals N single envs: env i of a vector reset with seed s
steps exactly like comorph.make(...) reset with seed s + i, through
same-step autoresets (final_obs / final_info), with 1 and with 2 threads."""
import numpy as np
import pytest

import comorph
from conftest import actions

N = 3


def single_rollouts(config_dir, seed, acts, modules):
    """What the vector must return, built from N single envs with same-step autoreset."""
    envs = [comorph.make(modules=modules, config_dir=config_dir) for _ in range(N)]
    obs0 = [e.reset(seed=seed + i)[0] for i, e in enumerate(envs)]
    steps = []
    for a in acts:
        row = []
        for i, e in enumerate(envs):
            obs, reward, terminated, truncated, info = e.step(a[i])
            final = None
            if terminated or truncated:
                final = (obs, info)
                obs, _ = e.reset()  # the next seed of env i's stream
            row.append((obs, reward, terminated, truncated, info, final))
        steps.append(row)
    return obs0, steps


@pytest.mark.parametrize("threads", [1, 2])
def test_vector_env_equals_single_envs(short_episodes, threads):
    acts = actions(5, 100).reshape(100, 1, 5).repeat(N, axis=1) * np.array([1.0, 0.5, -1.0])[None, :, None]
    acts = np.clip(acts, -1, 1).astype(np.float32)
    obs0, expected = single_rollouts(short_episodes, 1000, acts, 3)
    vec = comorph.VectorEnv(N, modules=3, config_dir=short_episodes, threads=threads)
    assert vec.threads == threads and vec.num_envs == N
    assert vec.observation_space["depth"].shape == (N, 1, 16, 16)
    obs, info = vec.reset(seed=1000)
    np.testing.assert_array_equal(info["seed"], [1000, 1001, 1002])
    for i in range(N):
        for k in obs:
            np.testing.assert_array_equal(obs[k][i], obs0[i][k])
    ended = 0
    for t, a in enumerate(acts):
        obs, reward, terminated, truncated, info = vec.step(a)
        assert reward.shape == (N,) and terminated.dtype == bool
        for i, (e_obs, e_reward, e_term, e_trunc, e_info, final) in enumerate(expected[t]):
            for k in obs:
                np.testing.assert_array_equal(obs[k][i], e_obs[k], err_msg=f"step {t} env {i} {k}")
            assert (reward[i], terminated[i], truncated[i]) == (e_reward, e_term, e_trunc)
            assert comorph.TERMINATIONS[info["reason"][i]] == e_info["termination"]
            assert info["_final_obs"][i] == (final is not None)
            if final is not None:
                ended += 1
                for k in obs:
                    np.testing.assert_array_equal(info["final_obs"][k][i], final[0][k])
                for key in ("T", "E", "D", "F", "episode_steps"):
                    assert info["final_info"][key][i] == final[1][key]
            else:
                assert np.isnan(info["final_info"]["F"][i])
    assert ended >= 2 * N  # 40-step episodes: every env autoreset at least twice


def test_vector_reset_takes_a_list_of_seeds():
    vec = comorph.VectorEnv(2, modules=2)
    obs, info = vec.reset(seed=[7, 3])
    np.testing.assert_array_equal(info["seed"], [7, 3])
    single = comorph.make(modules=2)
    np.testing.assert_array_equal(obs["state"][1], single.reset(seed=3)[0]["state"])
    with pytest.raises(ValueError, match="3 seeds for 2 envs"):
        vec.reset(seed=[1, 2, 3])
    with pytest.raises(ValueError, match="shape"):
        vec.step(np.zeros((3, 5), np.float32))
    with pytest.raises(ValueError, match=r"actions\[1\]\[4\]"):
        vec.step(np.array([[0, 0, 0, 0, 0], [0, 0, 0, 0, np.nan]], np.float32))
