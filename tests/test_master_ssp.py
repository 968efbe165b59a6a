"""SSP system files: writing, reading, parameter-binding forms, unsupported features."""
from __future__ import annotations

import dataclasses
import zipfile
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from orchestration import (Master, SystemFileError, UnknownComponentError, read_system,
                           simulate_system, write_ssd, write_ssp)

pytestmark = pytest.mark.integration

SSD_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="hand"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
"""


def hand_written(ramp: str, gain: str, system_extra: str = "", ramp_extra: str = "",
                 connection_extra: str = "", experiment: str = "") -> str:
    return SSD_HEAD + f"""
  <ssd:System name="hand">
    {system_extra}
    <ssd:Elements>
      <ssd:Component name="ramp" source="{ramp}">{ramp_extra}</ssd:Component>
      <ssd:Component name="gain" source="{gain}"/>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="ramp" startConnector="y" endElement="gain"
                      endConnector="u">{connection_extra}</ssd:Connection>
    </ssd:Connections>
  </ssd:System>
  {experiment}
</ssd:SystemStructureDescription>
"""


SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet version="1.0" name="ramp_values"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
  <ssv:Parameters>
    <ssv:Parameter name="slope"><ssv:Real value="4.0"/></ssv:Parameter>
  </ssv:Parameters>
</ssv:ParameterSet>
"""


@pytest.fixture()
def folder(tmp_path, fixture_fmus):
    """A folder with the two FMUs beside where the SSD will go."""
    for name in ("Ramp", "Gain"):
        (tmp_path / f"{name}.fmu").write_bytes(fixture_fmus[name].read_bytes())
    return tmp_path


def test_written_ssd_is_schema_valid_and_round_trips(ramp_gain, tmp_path):
    ramp_gain.start_time, ramp_gain.stop_time, ramp_gain.step_size = 0.0, 1.0, 0.125
    with pytest.raises(SystemFileError, match="not inside the SSD's folder"):
        write_ssd(ramp_gain, tmp_path / "elsewhere" / "SystemStructure.ssd")
    for component in ramp_gain.components:  # the FMUs beside the SSD, as the reader wants them
        (tmp_path / "sys" / "fmus").mkdir(parents=True, exist_ok=True)
        copy = tmp_path / "sys" / "fmus" / Path(component.source).name
        copy.write_bytes(Path(component.source).read_bytes())
    ramp_gain.components = [dataclasses.replace(c, source=tmp_path / "sys" / "fmus" / Path(c.source).name)
                            for c in ramp_gain.components]
    path = write_ssd(ramp_gain, tmp_path / "sys" / "SystemStructure.ssd")
    back = read_system(path.parent)  # a folder works too; read validates against the XSD
    assert [c.name for c in back.components] == ["ramp", "gain"]
    assert back.component("ramp").parameters == {"slope": 2.0, "offset": 1.0}
    assert [str(c) for c in back.connections] == [str(c) for c in ramp_gain.connections]
    assert (back.start_time, back.stop_time, back.step_size) == (0.0, 1.0, 0.125)
    assert back.fmu_path(back.components[0]) == ramp_gain.fmu_path(ramp_gain.components[0])


def test_ssp_archive_packs_the_fmus(ramp_gain, tmp_path):
    path = write_ssp(ramp_gain, tmp_path / "x.ssp")
    with zipfile.ZipFile(path) as archive:
        assert sorted(archive.namelist()) == ["SystemStructure.ssd", "resources/Gain.fmu",
                                              "resources/Ramp.fmu"]
    result = simulate_system(path, 1.0, 0.5)
    assert_allclose(result["gain.y"], [0.0, 6.0, 9.0])


def test_parameters_from_an_ssv_file_beside_the_ssd(folder):
    binding = """<ssd:ParameterBindings>
        <ssd:ParameterBinding source="ramp.ssv"/></ssd:ParameterBindings>"""
    (folder / "ramp.ssv").write_text(SSV)
    (folder / "SystemStructure.ssd").write_text(hand_written("Ramp.fmu", "Gain.fmu",
                                                             ramp_extra=binding))
    assert read_system(folder).component("ramp").parameters == {"slope": 4.0}
    with pytest.warns(UserWarning, match="unconnected"):
        result = simulate_system(folder / "SystemStructure.ssd", 1.0, 0.5)
    assert_allclose(result["ramp.y"], [0.0, 2.0, 4.0])


def test_system_level_binding_with_prefix_and_experiment(folder):
    binding = """<ssd:ParameterBindings><ssd:ParameterBinding prefix="ramp.">
        <ssd:ParameterValues>
          <ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>
            <ssv:Parameter name="offset"><ssv:Real value="5"/></ssv:Parameter>
          </ssv:Parameters></ssv:ParameterSet>
        </ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>"""
    experiment = '<ssd:DefaultExperiment startTime="1" stopTime="2"/>'
    path = folder / "SystemStructure.ssd"
    path.write_text(hand_written("Ramp.fmu", "Gain.fmu", system_extra=binding,
                                 experiment=experiment))
    system = read_system(path)
    assert system.component("ramp").parameters == {"offset": 5.0}
    assert (system.start_time, system.stop_time) == (1.0, 2.0)
    with pytest.warns(UserWarning):
        result = simulate_system(system, step_size=0.5)
    assert_allclose(result["time"], [1.0, 1.5, 2.0])
    assert_allclose(result["ramp.y"], [5.0, 6.5, 7.0])


def test_system_level_parameter_for_an_unknown_component(folder):
    binding = """<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>
          <ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>
            <ssv:Parameter name="ghost.k"><ssv:Real value="5"/></ssv:Parameter>
          </ssv:Parameters></ssv:ParameterSet>
        </ssd:ParameterValues></ssd:ParameterBinding></ssd:ParameterBindings>"""
    (folder / "SystemStructure.ssd").write_text(hand_written("Ramp.fmu", "Gain.fmu",
                                                             system_extra=binding))
    with pytest.raises(UnknownComponentError, match="ghost"):
        read_system(folder)


@pytest.mark.parametrize("kwargs, match", [
    ({"ramp_extra": '<ssd:ParameterBindings><ssd:ParameterBinding>'
                    '<ssd:ParameterMapping source="m.ssm"/></ssd:ParameterBinding>'
                    '</ssd:ParameterBindings>'}, "parameter mappings are not supported"),
    ({"connection_extra": '<ssc:BooleanMappingTransformation><ssc:MapEntry source="true" '
                          'target="false"/></ssc:BooleanMappingTransformation>'},
     "BooleanMappingTransformation on connections is not supported"),
    ({"system_extra": '<ssd:ParameterBindings><ssd:ParameterBinding source="../../x.ssv"/>'
                      '</ssd:ParameterBindings>'}, "outside the system's folder"),
    ({"ramp_extra": "<ssd:Bogus/>"}, "not valid SSP 1.0: ERROR .*Bogus"),
])
def test_unsupported_or_invalid_ssd(folder, kwargs, match):
    (folder / "SystemStructure.ssd").write_text(hand_written("Ramp.fmu", "Gain.fmu", **kwargs))
    with pytest.raises(SystemFileError, match=match) as caught:
        read_system(folder)
    assert caught.value.file.endswith("SystemStructure.ssd")


def test_missing_and_malformed_files(folder):
    with pytest.raises(SystemFileError, match="not found"):
        read_system(folder / "nothing.ssp")
    (folder / "bad.ssd").write_text("<ssd:Sys")
    with pytest.raises(SystemFileError, match="well-formed"):
        read_system(folder / "bad.ssd")
    (folder / "SystemStructure.ssd").write_text(hand_written("Missing.fmu", "Gain.fmu"))
    with pytest.raises(SystemFileError, match=r"Missing\.fmu.*component 'ramp'"):
        Master(folder)


def test_ssp_extraction_folder_goes_with_the_system(ramp_gain, tmp_path):
    import gc

    system = read_system(write_ssp(ramp_gain, tmp_path / "y.ssp"))
    workdir = system.base_dir
    assert (workdir / "resources" / "Ramp.fmu").is_file()
    del system
    gc.collect()
    assert not workdir.exists()
    assert np.isfinite(simulate_system(tmp_path / "y.ssp", 0.5, 0.25)["gain.y"]).all()


def test_entity_declarations_are_refused(folder):
    dtd = ('<!DOCTYPE x [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;">'
           '<!ENTITY xxe SYSTEM "file:///etc/passwd">]>\n')
    text = hand_written("Ramp.fmu", "Gain.fmu").replace('?>\n', '?>\n' + dtd, 1)
    (folder / "SystemStructure.ssd").write_text(text.replace('name="hand">', 'name="&b;">', 1))
    with pytest.raises(SystemFileError, match="DOCTYPE"):
        read_system(folder)
    (folder / "SystemStructure.ssd").write_text(text.replace('name="hand">', 'name="&xxe;">', 1))
    with pytest.raises(SystemFileError, match="external entity|DOCTYPE"):
        read_system(folder)
