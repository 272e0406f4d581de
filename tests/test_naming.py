"""One parameter naming everywhere (issue 9, first hour): the CLI's ``--set`` takes what the
Python API takes and the other way round, and every "unknown" error lists the close names.

Each check compares two ways of saying the same thing; the expected value is the one written
in the test (the value set), never an earlier run's output."""

from __future__ import annotations

import pytest

import chainmodel
from chainmodel import cli
from chainmodel import parameters as P
from chainmodel.scene import SETTINGS, load_scene


@pytest.mark.parametrize("name", ["chain.link_damping", "chain_link_damping"])
def test_python_api_takes_dotted_and_underscored_names(name):
    by_kw = load_scene("xu2010", **{name: 37.0})
    by_params = load_scene("xu2010").with_overrides(parameters={name: 37.0})
    assert by_kw.parameters["chain.link_damping"] == 37.0
    assert by_params.parameters["chain.link_damping"] == 37.0
    assert P.validate({name: 37.0})["chain.link_damping"] == 37.0


def _scene_from_cli(monkeypatch, *sets):
    """The scene `chainmodel run xu2010 --set ...` would simulate (captured, not run)."""
    seen = {}

    def fake_simulate(scene, **kw):
        seen["scene"] = scene
        raise KeyboardInterrupt          # stop before any simulation
    monkeypatch.setattr(chainmodel.simulation, "simulate", fake_simulate)
    argv = ["run", "xu2010", "--quiet"]
    for s in sets:
        argv += ["--set", s]
    assert cli.main(argv) == 130
    return seen["scene"]


@pytest.mark.parametrize("setting", ["chain.link_damping=41", "chain_link_damping=41"])
def test_cli_set_takes_both_forms(monkeypatch, setting):
    assert _scene_from_cli(monkeypatch, setting).parameters["chain.link_damping"] == 41.0


def test_cli_set_takes_the_scene_settings_the_api_takes(monkeypatch):
    sc = _scene_from_cli(monkeypatch, "input_speed_rpm=60", "load_torque=10", "fidelity=modal",
                         "input_shaft_rigid=true", "static_tension=900")
    api = load_scene("xu2010", input_speed_rpm=60, load_torque=10, fidelity="modal",
                     input_shaft_rigid=True, static_tension=900)
    assert sc.operating == api.operating
    assert sc.parameters == api.parameters


@pytest.mark.parametrize("typo, expected", [
    ("chain.link_dampng", "chain.link_damping"),
    ("chain_link_dampin", "chain.link_damping"),
    ("link_mass", "chain.link_mass"),
    ("input_speed_rmp", "input_speed_rpm"),
    ("static_tensoin", "static_tension"),
])
def test_unknown_names_list_close_matches_in_library_and_cli(capsys, typo, expected):
    with pytest.raises(ValueError, match=f"unknown .*{typo!r}; did you mean .*{expected}"):
        load_scene("xu2010", **{typo: 1.0})
    assert cli.main(["run", "xu2010", "--set", f"{typo}=1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "did you mean" in err and expected in err


def test_validate_lists_close_parameter_names():
    with pytest.raises(ValueError, match="did you mean chain.pretension"):
        P.validate({"chian.pretension": 1.0})


def test_every_setting_name_is_accepted():
    """Each scene setting and each parameter (both forms) is a name with_overrides knows: none
    of them is refused as unknown (values may still be refused for their range)."""
    from chainmodel.scene import setting_names
    names = setting_names()
    assert set(SETTINGS) <= set(names)
    for p in P.PARAMETERS:
        assert p.name in names and p.name.replace(".", "_") in names
        assert P.canonical_name(p.name.replace(".", "_")) == p.name
