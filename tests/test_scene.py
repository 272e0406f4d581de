"""Scenes, the parameter schema and simulate(): construction, overrides, validation."""

import math
from pathlib import Path

import numpy as np
import pytest

import chainmodel
from chainmodel import parameters as P
from chainmodel.models.kinematic import static_span_tension
from chainmodel.presets import preset, preset_names, reference_values
from chainmodel.scene import RPM, OperatingPoint, Scene, load_scene


def test_every_default_validates_and_every_real_has_a_unit_or_is_dimensionless():
    values = P.validate({})
    for p in P.PARAMETERS:
        assert p.description
        assert values[p.name] == p.check(p.default)


@pytest.mark.parametrize("name,value,fragment", [
    ("drive.pitch", 0.0, "drive.pitch"),
    ("drive.driver_teeth", 2, "drive.driver_teeth"),
    ("drive.driver_teeth", 12.5, "whole number"),
    ("chain.link_mass", -1.0, "chain.link_mass"),
    ("solver.method", "euler", "rk4"),
    ("input_shaft.rigid", "maybe", "true or false"),
    ("fidelity", 7, "fidelity"),
    ("gravity", math.nan, "finite"),
])
def test_bad_parameters_name_themselves(name, value, fragment):
    with pytest.raises(ValueError, match=fragment):
        P.validate({name: value})


def test_unknown_parameter_suggests_the_close_name():
    with pytest.raises(ValueError, match="did you mean chain.link_mass"):
        P.validate({"link_mass": 1.0})


def test_fidelity_accepts_names():
    assert [P.fidelity_level(n) for n in P.FIDELITY_NAMES] == [0, 1, 2, 3]


def test_xu2010_scene_is_the_paper_example():
    v = reference_values("multibody_example_xu2010.csv")
    sc = load_scene("xu2010")
    d = sc.drive
    assert (d.n_driver, d.n_driven, d.links) == (v["z1"], v["z2"], v["links"])
    assert d.centre_distance == pytest.approx(v["center_distance"], rel=1e-12)
    assert sc.operating.speed == pytest.approx(v["input_speed"] * 2 * math.pi / 60)
    assert sc.operating.load_torque == v["M_load"]
    assert sc.parameters["chain.link_stiffness"] == v["k_link"]
    assert sc.parameters["contact.stiffness"] == v["k_contact"]
    assert sc.parameters["input_shaft.stiffness"] == v["k_shaft"]


@pytest.mark.parametrize("name", preset_names())
def test_every_preset_makes_a_scene_with_a_drive(name):
    sc = load_scene(name)
    assert sc.drive.n_driver == preset(name).n_driver
    assert sc.drive.links is not None


def test_operating_profile_integrates_its_speed():
    op = OperatingPoint(speed=12.0, ramp_time=0.05, load_torque=1.0)
    t = np.linspace(0, 0.2, 4001)
    speed = np.array([op.inputs(x).speed for x in t])
    angle = np.array([op.inputs(x).angle for x in t])
    # trapezoidal integral of the (piecewise linear) speed is exact on this grid
    integral = np.concatenate([[0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(t))])
    np.testing.assert_allclose(angle, integral, atol=1e-12)
    assert op.inputs(0.01).acceleration == pytest.approx(12.0 / 0.05)
    assert op.inputs(0.1).acceleration == 0.0


def test_overrides_by_keyword_and_underscore_names():
    sc = load_scene("xu2010", fidelity="kinematic", chain_link_damping=50, input_speed_rpm=60,
                    load_torque=10.0)
    assert sc.fidelity == 0
    assert sc.parameters["chain.link_damping"] == 50
    assert sc.operating.speed == pytest.approx(60 * RPM)
    with pytest.raises(ValueError, match="unknown scene setting"):
        load_scene("xu2010", colour="red")


def test_static_tension_sets_the_pretension():
    sc = load_scene("xu2010", static_tension=2000.0)
    # to the search's tolerance, 1e-6 relative (scene._search_pretension)
    assert sc.model().static_tension() == pytest.approx(2000.0, rel=1e-6)
    with pytest.raises(ValueError, match="static_tension"):
        load_scene("xu2010", static_tension=10.0)  # less than the centre distance gives


def test_toml_scene(tmp_path):
    f = tmp_path / "s.toml"
    f.write_text('preset = "C1"\nfidelity = 0\nduration = 0.2\n[operating]\n'
                 'input_speed_rpm = 100\nload_torque = 5.0\n[parameters]\n"chain.link_damping" = 3.0\n')
    sc = load_scene(str(f))
    assert sc.name == "s"
    assert sc.drive.n_driver == 12 and sc.duration == 0.2
    assert sc.parameters["chain.link_damping"] == 3.0
    assert sc.operating.speed == pytest.approx(100 * RPM)
    f.write_text('preset = "C1"\nspeed = 3\n')
    with pytest.raises(ValueError, match="unknown keys"):
        load_scene(str(f))
    f.write_text('preset = "C1\n')
    with pytest.raises(ValueError, match="not valid TOML"):
        load_scene(str(f))


def test_unknown_scene_lists_presets():
    with pytest.raises(ValueError, match="xu2010"):
        load_scene("nonesuch")


def test_simulate_level0_tooth_ratio_and_result_access(tmp_path):
    r = chainmodel.simulate("xu2010", fidelity="kinematic", duration=0.3, output_interval=2e-4)
    s = r.summary()
    assert s["tooth_ratio"] == pytest.approx(25 / 17, rel=1e-9)
    assert r["driven.speed"].shape == r.time.shape
    assert np.all(np.isfinite(np.column_stack([r[n] for n in r.names])))
    with pytest.raises(KeyError, match="outputs are"):
        r["nonesuch"]
    path = r.to_csv(tmp_path / "out.csv")
    head = path.read_text().splitlines()[:2]
    assert head[0].startswith("time,driver.angle")
    assert head[1].startswith("s,rad")


def test_simulate_rejects_bad_durations():
    with pytest.raises(ValueError, match="duration"):
        chainmodel.simulate("xu2010", fidelity=0, duration=-1.0)
    with pytest.raises(ValueError, match="output_interval"):
        Scene("x", {}, duration=0.1, output_interval=0.2)


def test_iso606_chain_and_seat_radius_limits():
    """ISO 606 10B (the xu2010 chain): pitch 15.875 mm, roller 10.16 mm; seating-curve radius
    limits 0.505 d1 and 0.505 d1 + 0.069 d1^(1/3) (d1 in mm)."""
    from chainmodel.presets import iso606
    c = iso606("10B")
    assert c.pitch == pytest.approx(15.875e-3) and c.roller_radius == pytest.approx(5.08e-3)
    lo, hi = c.seat_radius_range()
    assert lo == pytest.approx(0.505 * 10.16e-3)
    assert hi == pytest.approx((0.505 * 10.16 + 0.069 * 10.16 ** (1 / 3)) * 1e-3)
    with pytest.raises(ValueError, match="10B"):
        iso606("99Z")


# --- the boundary against what a fuzzing user typed (eighteenth session of issue 21) ----------

@pytest.mark.parametrize("kw, fragment", [
    # a pitch of the wrong type on a scene that names its chain: the range, not the chain check
    (dict(drive_pitch="0.0254"), r"drive\.pitch must be a finite number in \(0, 1\].*'0\.0254'"),
    (dict(drive_pitch=math.nan), r"drive\.pitch must be a finite number"),
    # typos far outside any chain drive: refused with the range, not an overflow
    (dict(driver_inertia=1e300), r"driver\.inertia must be in \(0, 1e\+06\]"),
    (dict(drive_centre_distance=1e300), r"drive\.centre_distance must be in \[0, 1000\]"),
    (dict(chain_link_stiffness=1e20), r"chain\.link_stiffness must be in \(0, 1e\+11\]"),
    (dict(parameters={1: 2.0}), r"parameter names must be strings.*1 \(int\)"),
    (dict(parameters=[("chain.link_damping", 1.0)]), r"parameters must be a mapping.*list"),
    # rollers wider than half a pitch overlap their neighbours (ISO 606: d1 = 0.62-0.67 p)
    (dict(chain_roller_radius=0.009, contact_seat_radius=0.0095),
     r"chain\.roller_radius \(0\.009 m\) must be below half of drive\.pitch"),
    (dict(input_speed_rpm=100, input_speed=10), r"either input_speed_rpm .* or input_speed"),
])
def test_bad_values_at_the_library_boundary_name_themselves(kw, fragment):
    with pytest.raises(ValueError, match=fragment):
        load_scene("xu2010", **kw)


@pytest.mark.parametrize("text, fragment", [
    ('name = "x"\nparameters = 5\n', r"parameters must be a table.*got 5"),
    ('name = "x"\noperating = "fast"\n', r"operating must be a table.*'fast'"),
    ("name = 5\n", r"name must be a string.*got 5"),
])
def test_malformed_scene_files_name_the_key(tmp_path, text, fragment):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError, match=fragment):
        load_scene(str(path))


def test_a_binary_scene_file_is_named():
    import tempfile
    with tempfile.NamedTemporaryFile(suffix=".toml", delete=False) as fh:
        fh.write(b"\xff\xfe\x00")
    try:
        with pytest.raises(ValueError, match=r"not a text file in UTF-8") as err:
            load_scene(fh.name)
        assert fh.name in str(err.value)
    finally:
        import os
        os.unlink(fh.name)


def test_naming_another_chain_replaces_the_presets_chain_values_not_the_given_ones():
    """xu2010 carries seed 003's 10B values; naming the 16B chain takes the 16B's (ISO 606:
    25.4 mm pitch, 15.88 mm roller), except a value given by hand."""
    from chainmodel import chains
    sc = load_scene("xu2010", chain="16B", drive_pitch=0.0254, drive_links=40)
    values = chains.parameter_values("16B")
    assert sc.chain == "16B"
    for key in ("chain.link_mass", "chain.link_stiffness", "contact.stiffness",
                "chain.roller_radius"):
        assert sc.parameters[key] == values[key], key
    mine = load_scene("xu2010", chain="16B", drive_pitch=0.0254, drive_links=40,
                      chain_link_mass=0.2)
    assert mine.parameters["chain.link_mass"] == 0.2
    assert load_scene("xu2010").parameters["contact.stiffness"] == 8.46e6     # seed 003


def test_a_chain_far_too_long_is_warned_at_levels_0_and_1_not_a_crash():
    """300 links on xu2010's 197.7 mm (46 pitches wrap): level 3's statics meet a degenerate
    layout; levels 0-1 fall back to the seat ladder and say the chain is too long."""
    for level in (0, 1):
        r = chainmodel.simulate("xu2010", fidelity=level, drive_links=300, duration=0.02,
                                output_interval=1e-3)
        assert any("the chain is too long: drive.links = 300" in w for w in r.warnings)


def test_a_steady_window_shorter_than_a_tooth_period_is_warned_not_a_silent_nan():
    """xu2010 at 3 rpm: a driver tooth period is 2 pi / 25 / (3 rpm) = 0.8 s, the steady half of
    a 1 s run 0.5 s; the tooth ratio is undefined there, and the warning says how long to run."""
    r = chainmodel.simulate("xu2010", input_speed_rpm=3, duration=1.0, fidelity=1)
    assert math.isnan(r.summary()["tooth_ratio"])
    (text,) = [w for w in r.warnings if "less than one driver tooth period" in w]
    period = 2 * math.pi / 25 / (3 * RPM)
    assert f"({period:.3g} s" in text
    longer = chainmodel.simulate("xu2010", input_speed_rpm=3, duration=1.7, fidelity=1)
    assert not any("less than one driver tooth period" in w for w in longer.warnings)
    assert longer.summary()["tooth_ratio"] == pytest.approx(25 / 17, rel=1e-3)   # z1 / z2


def test_a_drive_held_at_rest_is_not_asked_for_a_longer_run():
    """Input speed 0 (a drive held at rest): no tooth period exists; the summary says so
    instead of asking for a run of ~1e13 s (an audit found "run for at least 4.71e+13 s": the
    driver's residual vibration taken for a running speed)."""
    r = chainmodel.simulate("xu2010", input_speed_rpm=0.0, duration=0.1, fidelity=1)
    assert math.isnan(r.summary()["tooth_ratio"])
    assert not any("run for at least" in w for w in r.warnings)
    assert any("held at rest" in w for w in r.warnings)


def test_a_chain_value_far_from_its_iso_chain_is_questioned():
    """A link mass typed in grams (16.2 'kg' at 15.875 mm, whose ISO 606 chains 10A / 10B have
    0.0206 / 0.0177 kg per link, chainmodel.chains): the speed refusal it causes names it, and a
    run that goes ahead carries the question in its warnings (chainmodel.validity, which the FMU
    logs too). Values within 30x are not questioned, nor any preset's."""
    from chainmodel import chains
    refs = {n: chains.parameter_values(n)["chain.link_mass"] for n in chains.chains_of_pitch(0.015875)}
    name, ref = min(refs.items(), key=lambda kv: abs(math.log(16.2 / kv[1])))
    with pytest.raises(ValueError, match=r"check the chain first: chain\.link_mass = 16\.2 kg "
                                         r"is .* x the value of the nearest ISO 606 chain"):
        chainmodel.simulate("xu2010", chain_link_mass=16.2, duration=0.01)
    r = chainmodel.simulate("xu2010", fidelity=0, chain_link_mass=16.2, input_speed_rpm=10,
                            duration=0.2, output_interval=1e-3)
    (text,) = [w for w in r.warnings if "a unit slip?" in w]
    assert f"{16.2 / ref:.3g} x" in text and f"({name}: " in text
    assert load_scene("xu2010", chain_link_mass=20 * min(refs.values())).implausible_chain_values() == []
    for preset_name in preset_names():
        assert load_scene(preset_name).implausible_chain_values() == [], preset_name



def test_a_static_tension_refusal_names_a_chain_value_far_from_its_chain():
    """The twenty-fourth session's audit: a 16B link mass typed 100x too large makes the sag
    alone exceed the mixer's 1200 N static tension, and the refusal spoke of the centre
    distance only. It now names the mass too (docs/scenes.md rule 5: "in any refusal it
    causes"). The 16B's own mass is the steel-volume law's (chainmodel.chains)."""
    from chainmodel import chains
    mass = 100 * chains.parameter_values("16B")["chain.link_mass"]
    scene = load_scene(str(Path(__file__).resolve().parent.parent / "examples" / "scenes"
                           / "16b_mixer.toml"))
    with pytest.raises(ValueError, match=r"static_tension 1200 N is below .* but check the "
                                         r"chain first: chain\.link_mass = .* is 100 x the "
                                         r"value of the nearest ISO 606 chain of this pitch "
                                         r"\(16B: "):
        scene.with_overrides(parameters={"chain.link_mass": mass})

def test_a_drive_changed_from_a_preset_drops_the_presets_notes_on_its_drive():
    """xu2010's note ("centre distance 197.7 mm as in the paper") is false for an 11/57 drive
    built on it: it goes, and the notes say which drive values were given."""
    base = Scene.from_preset("xu2010")
    assert any("197.7 mm" in n for n in base.notes)
    assert base.with_overrides(input_speed_rpm=300).notes == base.notes   # same drive
    other = base.with_overrides(parameters={"drive.driver_teeth": 11, "drive.driven_teeth": 57,
                                            "drive.links": 111})
    assert not any("197.7 mm" in n for n in other.notes)
    assert any("drive.driver_teeth" in n and "drive.links" in n and "xu2010" in n
               for n in other.notes)


def test_an_odd_link_count_is_noted_and_a_file_of_its_own_says_nothing_changed(tmp_path):
    """A roller chain alternates inner and outer links, so 71 links close only with an offset
    link (the audit's F6): noted, with the even counts either side; 70 and 72 are not. A scene
    file with no preset is not "changed from" anything: its notes do not say so."""
    path = tmp_path / "own.toml"
    path.write_text('chain = "16B"\n[operating]\ninput_speed_rpm = 100\nload_torque = 50\n'
                    '[parameters]\n"drive.driver_teeth" = 15\n"drive.driven_teeth" = 30\n'
                    '"drive.links" = 70\n')
    scene = load_scene(str(path))
    assert not any("changed from" in n for n in scene.notes)
    for links, odd in ((70, False), (71, True), (72, False)):
        notes = scene.with_overrides(parameters={"drive.links": links}).notes
        said = [n for n in notes if "offset (cranked) link" in n]
        assert bool(said) == odd, (links, notes)
        if odd:
            assert f"({links})" in said[0] and f"{links + 1} or {links - 1} links" in said[0]


def test_a_default_sprocket_inertia_on_another_sprocket_is_noted(tmp_path):
    """The schema's sprocket inertias are seed 003's xu2010 sprockets (25 and 17 teeth of
    15.875 mm pitch). A file of another drive that leaves them is told so, with the steel
    disc of its own sprocket, rho pi w d^4 / 32 with d = p / sin(pi / z) and w = 0.93 b1
    (ISO 606 08B: b1 = 7.75 mm), computed here; given inertias, xu2010 itself and a preset
    with its own (C1, seed 004 Table 2) get no such note."""
    path = tmp_path / "own.toml"
    path.write_text('chain = "08B"\n[operating]\ninput_speed_rpm = 100\nload_torque = 5\n'
                    '[parameters]\n"drive.driver_teeth" = 13\n"drive.driven_teeth" = 39\n'
                    '"drive.links" = 110\n')
    notes = [n for n in load_scene(str(path)).notes if n.startswith("default inertia:")]
    assert [n.split()[2] for n in notes] == ["driver.inertia", "driven.inertia"]
    for note, z in zip(notes, (13, 39)):
        disc = 7850 * math.pi * 0.93 * 7.75e-3 * (12.7e-3 / math.sin(math.pi / z)) ** 4 / 32
        assert f"{z}-tooth 08B one" in note and f"would be {disc:.3g} kg.m2" in note
    given = load_scene(str(path), driver_inertia=1e-4, driven_inertia=3e-3).notes
    assert not any(n.startswith("default inertia:") for n in given)
    for name in ("xu2010", "C1"):
        assert not any(n.startswith("default inertia:") for n in load_scene(name).notes)


def test_a_static_tension_below_the_sag_at_the_tight_wrap_is_told_to_shorten_the_centres():
    """At drive.centre_distance = 0 (the tight wrap, new-scene's default) more links only
    lengthen the spans and raise the sag tension (an audit: 110 -> 130 links, 381 -> 470 N), so
    the refusal asks for a centre distance below the tight one, and that lowers the tension."""
    base = dict(chain="16B", drive_driver_teeth=19, drive_driven_teeth=38, drive_pitch=0.0254,
                input_speed_rpm=100.0, load_torque=50.0, chain_pretension=0.0, fidelity=1)
    tight = {n: load_scene("xu2010", drive_links=n, drive_centre_distance=0.0, **base)
             for n in (110, 130)}
    floors = {n: sc.model().static_tension() for n, sc in tight.items()}
    assert floors[130] > floors[110]
    a = tight[110].drive.centre_distance
    with pytest.raises(ValueError, match=rf"give drive\.centre_distance below the "
                                         rf"{1e3 * a:.5g} mm at which these 110 links wrap"):
        load_scene("xu2010", drive_links=110, drive_centre_distance=0.0,
                   **dict(base, chain_pretension=None), static_tension=50.0)
    shorter = load_scene("xu2010", drive_links=110, drive_centre_distance=a - 0.01, **base)
    assert shorter.model().static_tension() < floors[110]


def test_a_default_input_shaft_on_another_drive_is_noted_with_its_wind_up(tmp_path):
    """The schema's input shaft is xu2010's (seed 003, 12 kN.m/rad). A heavy drive left on it
    (an audit's 16A 11/55 at 9000 N.m) is told the torque its load puts on the shaft, load x
    z1 / z2, and the wind-up, that over the stiffness, both computed here; a given stiffness,
    a rigid shaft and xu2010 itself get no such note."""
    path = tmp_path / "heavy.toml"
    path.write_text('chain = "16A"\n[operating]\ninput_speed_rpm = 50\nload_torque = 9000\n'
                    '[parameters]\n"drive.driver_teeth" = 11\n"drive.driven_teeth" = 55\n'
                    '"drive.links" = 120\n')
    notes = [n for n in load_scene(str(path)).notes if n.startswith("default shaft:")]
    torque = 9000.0 * 11 / 55
    assert len(notes) == 1 and f"about {torque:.4g} N.m" in notes[0]
    assert f"winding it {torque / 12000.0:.3g} rad" in notes[0]
    for kw in ({"input_shaft_stiffness": 1e6}, {"input_shaft_rigid": True}):
        assert not any(n.startswith("default shaft:") for n in load_scene(str(path), **kw).notes)
    assert not any(n.startswith("default shaft:") for n in load_scene("xu2010").notes)
