"""Seeded fuzz of the config loader over the shipped configs (issue 10, item 1).

Every mutant (see ``tests/config_mutants.py``) must be either a valid config, or one
:class:`ConfigError` naming the file, a line and, for a mutated value, the key path: never
another exception. Mutants are checked with :func:`validate_config`, which runs what
``baseline``/``train`` check before they start. A few valid mutants are then run for a few
real SUMO steps.
"""

from __future__ import annotations

import collections
import logging
import random
from pathlib import Path

import numpy as np
import pytest

from flowrun.envs.factory import make_env
from flowrun.errors import ConfigError
from flowrun.preflight.checks import validate_config
from tests.config_mutants import (
    SHIPPED,
    Mutant,
    check_outcome,
    data_mutants,
    text_mutants,
    write,
)

#: Data mutants checked per config and kind (seeded sample; every kind of every config).
PER_KIND = {"drop": 10, "unknown_key": 5}
PER_REPLACE_KIND = 5
#: Text mutants YAML can never read as a valid config.
ALWAYS_REFUSED = ("bytes:nul", "bytes:garbage", "alias_bomb", "alias_recursive",
                  "alias_undefined", "deep_nesting", "duplicate_key")  # fmt: skip
#: Mappings whose keys are free (an unknown key there is not an error).
FREE_MAPPINGS = ("additional_params", "rllib", "model_config")


def sample(path: Path, seed: int) -> list[Mutant]:
    """A seeded sample of ``path``'s data mutants, by kind, plus all its text mutants."""
    rng = random.Random(f"{path.stem}-{seed}")
    by_kind: dict[str, list[Mutant]] = collections.defaultdict(list)
    for mutant in data_mutants(path, rng, per_leaf=3):
        by_kind[mutant.kind].append(mutant)
    chosen = []
    for kind, mutants in sorted(by_kind.items()):
        n = PER_KIND.get(kind, PER_REPLACE_KIND)
        chosen += rng.sample(mutants, min(n, len(mutants)))
    return chosen + text_mutants(path, rng)


def outcome(tmp: Path, mutant: Mutant, index: int) -> tuple[str, str | None]:
    """``("valid" | "refused", problem or None)`` of one mutant."""
    file = write(tmp, mutant, index)
    try:
        validate_config(file)
    except ConfigError as err:
        return "refused", check_outcome(err, file, mutant)
    except Exception as err:  # what the fuzz is looking for
        return "crash", f"{type(err).__name__}: {err}"
    must_fail = mutant.kind in ALWAYS_REFUSED or (
        mutant.kind == "unknown_key" and not set(mutant.at) & set(FREE_MAPPINGS)
    )
    return "valid", "accepted" if must_fail else None


@pytest.fixture(autouse=True)
def _quiet(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.ERROR)  # ignored-setting warnings of valid mutants


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_every_mutant_is_valid_or_one_located_error(path: Path, tmp_path: Path) -> None:
    mutants = sample(path, seed=0)
    counts: collections.Counter[str] = collections.Counter()
    problems = []
    for i, mutant in enumerate(mutants):
        result, problem = outcome(tmp_path, mutant, i)
        counts[result] += 1
        if problem:
            problems.append(f"{mutant.kind} at {mutant.at}: {problem}")
    assert not problems, "\n".join(problems)
    assert counts["refused"] > len(mutants) // 2  # the mutants do break things


def test_the_sample_covers_every_kind_of_mutation() -> None:
    kinds = {m.kind for m in sample(SHIPPED[0], seed=0)}
    assert {"drop", "unknown_key", "replace:nan", "replace:inf", "replace:huge",
            "replace:negative", "replace:zero", "replace:string", "replace:list",
            "replace:wrong_type", "tab", "duplicate_key", "alias_bomb", "bytes:nul",
            "bytes:latin1", "syntax:unclosed_bracket", "deep_nesting"} <= kinds  # fmt: skip


RUNNABLE = ("sugiyama", "sugiyama_noise", "ring_wave", "figure_eight")


@pytest.mark.sumo
def test_valid_mutants_run(tmp_path: Path) -> None:
    """Four seeded valid value mutants of ring and figure-eight configs run five steps."""
    rng = random.Random(7)
    candidates = [
        mutant
        for path in SHIPPED
        if path.stem in RUNNABLE
        for mutant in data_mutants(path, rng, per_leaf=2)
        if mutant.kind.startswith("replace:") and mutant.at[0] != "train"
    ]
    rng.shuffle(candidates)
    valid = []
    for i, mutant in enumerate(candidates):
        try:
            valid.append((mutant, validate_config(write(tmp_path, mutant, i))))
        except ConfigError:
            continue
        if len(valid) == 4:
            break
    assert len(valid) == 4
    for mutant, cfg in valid:
        env = make_env(cfg)
        try:
            env.reset(seed=0)
            for _ in range(5):
                shape = env.action_space.shape or (0,)
                _, reward, *_ = env.step(np.zeros(shape, dtype=np.float32))
            assert np.isfinite(reward), (mutant.kind, mutant.at)
        finally:
            env.close()
