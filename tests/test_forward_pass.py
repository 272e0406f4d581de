"""Issue 20, item 4: one forward pass per run. simulate() loads the scene, applies the
overrides, chooses the level (auto), builds the model and stepper, runs and wraps the result,
each step handing the next what it needs: a scene is copied (Scene.with_overrides) once per
set of overrides and the drive's geometry is built once. The expected counts are derived from
those steps, not from a previous run."""

from __future__ import annotations

import collections

import pytest

import chainmodel
from chainmodel import scene as S
from chainmodel.scene import load_scene

RUN = {"duration": 0.01, "output_interval": 1e-3}


@pytest.fixture
def counts(monkeypatch):
    seen = collections.Counter()
    original = S.Scene.with_overrides

    def with_overrides(self, *args, **kw):
        seen["with_overrides"] += 1
        return original(self, *args, **kw)

    monkeypatch.setattr(S.Scene, "with_overrides", with_overrides)
    return seen


def _drives_built(fn):
    """Drives constructed while ``fn`` runs (Scene's drive cache emptied first: a run builds
    the geometry it needs, the cache only saves building it again)."""
    S._drive.cache_clear()
    before = S._drive.cache_info().misses
    out = fn()
    return out, S._drive.cache_info().misses - before


@pytest.mark.parametrize("name", ["xu2010", "C1"])
def test_a_fixed_level_run_copies_the_scene_once_per_override_set(name, counts):
    load_scene(name)
    loading = counts["with_overrides"]       # the preset's own (C1: Table 2's static tension)
    counts.clear()
    r, drives = _drives_built(lambda: chainmodel.simulate(name, fidelity=1, **RUN))
    assert r.fidelity == 1
    assert counts["with_overrides"] == loading + 1      # + the one set of overrides given
    assert drives == 1                                  # one geometry


def test_a_scene_without_overrides_is_run_as_it_is(counts):
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, **RUN)
    counts.clear()
    r, drives = _drives_built(lambda: chainmodel.simulate(sc))
    assert r.scene is sc
    assert counts["with_overrides"] == 0
    assert drives == 1


def test_auto_builds_each_scene_model_and_the_drive_once(counts, monkeypatch):
    from chainmodel import fidelity_auto
    built = collections.Counter()      # models made, by level (both places that make them)
    for module in (S, fidelity_auto):
        original = module.model_class

        def model_class(level, _original=original):
            built[level] += 1
            return _original(level)

        monkeypatch.setattr(module, "model_class", model_class)
    original_build = S.build_model       # Scene.model() builds through models.build_model

    def build_model(level, *args, _original=original_build):
        built[level] += 1
        return _original(level, *args)

    monkeypatch.setattr(S, "build_model", build_model)
    r, drives = _drives_built(lambda: chainmodel.simulate("xu2010", fidelity="auto", **RUN))
    choice = r.auto_choice
    # the overrides given, the scene at level 0 (the features the trade table is searched by),
    # and one scene per level checked, carrying that row's solver settings
    assert counts["with_overrides"] == 1 + 1 + len(choice.levels_checked)
    assert drives == 1
    assert r.scene is choice.scene and r.fidelity == choice.level
    # level 0 for the features, then one model per level checked; the run reuses the chosen one
    expected = collections.Counter({0: 1})
    expected.update(choice.levels_checked)
    assert built == expected


def test_a_resolved_choice_is_run_as_it_is_and_refuses_further_overrides(counts):
    """The CLI's path: resolve() once, print the choice, then simulate(choice=...) runs the
    choice's scene on the model it built, without copying the scene again."""
    from chainmodel.simulation import resolve
    sc, choice = resolve("xu2010", fidelity="auto", **RUN)
    counts.clear()
    r = chainmodel.simulate(sc, choice=choice)
    assert counts["with_overrides"] == 0
    assert r.scene is choice.scene and r.auto_choice is choice
    with pytest.raises(ValueError, match="resolve"):
        chainmodel.simulate(sc, choice=choice, duration=0.02)
