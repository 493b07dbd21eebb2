"""comorph.evaluate(path, episodes, seed, scenario) returns what `comorph
eval` writes to eval-<scenario>.json for the same run and seeds
(results/quick-hier-td3, copied: eval writes into the run directory), in a
working directory with the run's scene classifier (conftest.work)."""
import json
import shutil
import subprocess

import pytest

import comorph
from conftest import SOURCE_DIR, tool

RUN = SOURCE_DIR / "results" / "quick-hier-td3"


def test_evaluate_equals_comorph_eval(work, monkeypatch):
    run = work / "quick-hier-td3"
    shutil.rmtree(run, ignore_errors=True)
    shutil.copytree(RUN, run)
    (run / "eval-default.json").unlink()
    subprocess.run([tool("COMORPH_EXE"), "eval", "--run", "quick-hier-td3", "--episodes", "4", "--seed", "8100000"],
                   cwd=work, check=True, capture_output=True)
    cli = json.loads((run / "eval-default.json").read_text())
    monkeypatch.chdir(work)
    py = comorph.evaluate("quick-hier-td3", episodes=4, seed=8100000, scenario="default", workers=1)
    assert py == cli
    assert py["episodes"] == 4 and set(py["success_rate"]) == {"0.04", "0.06", "0.08", "avg"}
    assert sum(py["terminations"].values()) == 4


def test_scenarios_agree_with_the_cli_and_bad_ones_are_refused(work, monkeypatch):
    # The C++ registry's rows, as `comorph eval --scenario` knows them.
    assert comorph.SCENARIOS == {"default": (None, False), "obstacles7": (7, False), "obstacles8": (8, False),
                                 "mixed": (None, True)}
    monkeypatch.chdir(work)
    with pytest.raises(RuntimeError, match="unknown scenario 'stairs'"):
        comorph.evaluate(RUN, episodes=1, seed=1, scenario="stairs")
    with pytest.raises(ValueError, match="not a training run"):
        comorph.evaluate(work, episodes=1, seed=1)
