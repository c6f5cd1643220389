"""The built-in scene sections (:mod:`impactcont.scene.sections`): each is registered under
its key with its entry, driver, description and plot kinds, every ``"module:function"`` it
names resolves, its driver computes an entry; ``register_section`` adds a section and refuses
a reserved or taken key by name."""

from __future__ import annotations

import dataclasses

import pytest
import xarray as xr

from impactcont.scene import entries, sections, switches, tasks, twoparam
from impactcont.scene.keys import Where
from impactcont.scene.plugins import SceneSection, load_target, unregister_problem

BUILT_IN = {"orbits": (sections.ORBITS, entries.OrbitSpec, tasks.ORBITS),
            "branches": (sections.BRANCHES, entries.BranchSpec, tasks.BRANCHES),
            "robust": (sections.ROBUST, entries.RobustSpec, tasks.ROBUST),
            "simulations": (sections.SIMULATIONS, entries.SimulationSpec, tasks.SIMULATIONS),
            "curves": (sections.CURVES, twoparam.CurveSpec, twoparam.CURVES),
            "maps": (sections.MAPS, twoparam.MapSpec, twoparam.MAPS),
            "switches": (sections.SWITCHES, switches.SwitchSpec, switches.SWITCHES),
            "multi_impact": (sections.MULTI_IMPACT, switches.MultiImpactSpec,
                             switches.MULTI_IMPACT)}


def test_the_built_in_sections_run_in_registry_order() -> None:
    found = sections.scene_sections()
    assert list(found)[:8] == ["orbits", "branches", "robust", "simulations", "multi_impact",
                               "switches", "curves", "maps"]
    for key, (section, _, _) in BUILT_IN.items():
        assert found[key] is section and section.key == key


@pytest.mark.parametrize("key", list(BUILT_IN))
def test_every_name_a_section_gives_resolves_to_its_handler(key) -> None:
    section, entry, handler = BUILT_IN[key]
    section.check()  # the registry's own check of a section
    assert section.load_entry() is entry and entry.section == key
    for name, method in (("driver", "compute"), ("describe", "describe"),
                         ("special_points", "special_points")):
        resolved = load_target(getattr(section, name))
        assert resolved.__self__ is handler and resolved.__name__ == method
    for kind in section.plots:
        assert kind.section == key and callable(kind.load_draw())
        assert sections.plot_kinds()[kind.key] is kind
    assert isinstance(section.title, str) and section.title


def test_the_plot_kinds_draw_their_sections() -> None:
    kinds = sections.plot_kinds()
    assert kinds["bifurcation_diagram"].sections == ("branches", "switches", "multi_impact")
    assert kinds["map"].section == "maps" and not kinds["map"].many
    assert kinds["orbits"].many
    assert kinds["curves"].check is twoparam.check_curves_plot


def test_a_section_computes_and_describes_an_entry() -> None:
    where = Where("s.toml", "orbits[0]")
    osc = entries.OscillatorSpec.parse(
        {"K": [[1.0, -1.0], [-1.0, 2.0]], "F": [1.0, 0.0], "R": 0.6, "eta": 0.1, "b": 0.6,
         "omega": 1.0}, where).build()
    entry = entries.OrbitSpec.parse({"name": "o1"}, where, osc, 0)
    context = sections.RunContext(datasets={})
    ds = sections.ORBITS.compute(entry, context)
    xr.testing.assert_identical(ds, tasks.ORBITS.compute(entry))
    assert sections.ORBITS.describe_datasets({"o1": ds}) == tasks.ORBITS.describe({"o1": ds})
    assert sections.ORBITS.find_points({"o1": ds}) == []
    with pytest.raises(dataclasses.FrozenInstanceError):
        context.datasets = {}


def test_register_section_adds_a_section_and_refuses_a_reserved_or_taken_key() -> None:
    mine = dataclasses.replace(sections.ORBITS, key="my_orbits", plots=())
    sections.register_section(mine)
    try:
        assert sections.scene_sections()["my_orbits"] is mine
        with pytest.raises(ValueError, match=r"a problem 'my_orbits' is already registered"):
            sections.register_section(mine)
        sections.register_section(mine, replace=True)
    finally:
        unregister_problem("my_orbits")
    assert "my_orbits" not in sections.scene_sections()
    with pytest.raises(ValueError, match=r"problem name 'orbits' is taken by a built-in"):
        sections.register_section(sections.ORBITS)
    with pytest.raises(ValueError, match=r"section key 'plots' is reserved; allowed: any key "
                                         r"but title, description, oscillator, output, plots"):
        sections.register_section(dataclasses.replace(sections.ORBITS, key="plots", plots=()))
    with pytest.raises(ValueError, match=r"section key 'My-Orbits' is not allowed; allowed: "
                                         r"lower-case letters"):
        sections.register_section(SceneSection("My-Orbits", entries.OrbitSpec, print, "t"))
