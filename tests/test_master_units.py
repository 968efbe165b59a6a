"""SSP units, linear transformations, nested systems and system connectors; step fallback."""
from __future__ import annotations

import math
import zipfile

import numpy as np
import pytest
from numpy.testing import assert_allclose

from fmu_fixtures.fixtures import fixture_fmus  # noqa: F401 (fixture)
from orchestration import (Component, Connection, DefaultStepWarning,
                           IncompatibleConnectionError, Master, ScheduleError, StartValueError,
                           System, read_system, simulate_system, write_ssp)
from sarins.cli import main

pytestmark = pytest.mark.integration

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="units"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">
"""
UNITS = """  <ssd:Units>
    <ssc:Unit name="deg"><ssc:BaseUnit rad="1" factor="0.017453292519943295"/></ssc:Unit>
    <ssc:Unit name="rad"><ssc:BaseUnit rad="1"/></ssc:Unit>
    <ssc:Unit name="degC"><ssc:BaseUnit K="1" offset="273.15"/></ssc:Unit>
    <ssc:Unit name="K"><ssc:BaseUnit K="1"/></ssc:Unit>
  </ssd:Units>
"""


def real(name: str, kind: str, unit: str | None = None) -> str:
    unit_attribute = f' unit="{unit}"' if unit else ""
    return (f'<ssd:Connector name="{name}" kind="{kind}"><ssc:Real{unit_attribute}/>'
            "</ssd:Connector>")


def values(**named) -> str:
    entries = "".join(f'<ssv:Parameter name="{k}"><ssv:Real value="{v}"/></ssv:Parameter>'
                      for k, v in named.items())
    return ("<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>"
            f'<ssv:ParameterSet version="1.0" name="p"><ssv:Parameters>{entries}'
            "</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues></ssd:ParameterBinding>"
            "</ssd:ParameterBindings>")


# deg_source.y (deg) -> sub.angle_in -> sub.feed.angle (the FMU's rad)
# celsius.y (degC) -> sub.temp_in (K) -> sub.feed.u (K); sub.feed.y (K) -> sub.temp_out
# -> sink.u (degC, then 2 x + 1); the top-level input angle_ext has no source -> sink.angle
NESTED = HEAD + f"""
  <ssd:System name="top">
    <ssd:Connectors>{real("angle_ext", "input", "deg")}</ssd:Connectors>
    <ssd:Elements>
      <ssd:Component name="deg_source" source="Ramp.fmu">
        <ssd:Connectors>{real("y", "output", "deg")}</ssd:Connectors>{values(slope=90)}
      </ssd:Component>
      <ssd:Component name="celsius" source="Ramp.fmu">
        <ssd:Connectors>{real("y", "output", "degC")}</ssd:Connectors>
        {values(slope=1, offset=20)}
      </ssd:Component>
      <ssd:System name="sub">
        <ssd:Connectors>{real("angle_in", "input")}{real("temp_in", "input", "K")}
          {real("temp_out", "output")}</ssd:Connectors>
        <ssd:Elements>
          <ssd:Component name="feed" source="Feed.fmu">
            <ssd:Connectors>{real("angle", "input")}{real("u", "input", "K")}
              {real("y", "output", "K")}</ssd:Connectors>
          </ssd:Component>
        </ssd:Elements>
        <ssd:Connections>
          <ssd:Connection startConnector="angle_in" endElement="feed" endConnector="angle"/>
          <ssd:Connection startConnector="temp_in" endElement="feed" endConnector="u"/>
          <ssd:Connection startElement="feed" startConnector="y" endConnector="temp_out"/>
        </ssd:Connections>
      </ssd:System>
      <ssd:Component name="sink" source="Feed.fmu">
        <ssd:Connectors>{real("u", "input", "degC")}</ssd:Connectors>
      </ssd:Component>
    </ssd:Elements>
    <ssd:Connections>
      <ssd:Connection startElement="deg_source" startConnector="y" endElement="sub"
                      endConnector="angle_in"/>
      <ssd:Connection startElement="celsius" startConnector="y" endElement="sub"
                      endConnector="temp_in"/>
      <ssd:Connection startElement="sub" startConnector="temp_out" endElement="sink"
                      endConnector="u"><ssc:LinearTransformation factor="2" offset="1"/>
      </ssd:Connection>
      <ssd:Connection startConnector="angle_ext" endElement="sink" endConnector="angle"/>
    </ssd:Connections>
  </ssd:System>
{UNITS}</ssd:SystemStructureDescription>
"""


@pytest.fixture()
def folder(tmp_path, fixture_fmus):
    for name in ("Ramp", "Feed"):
        (tmp_path / f"{name}.fmu").write_bytes(fixture_fmus[name].read_bytes())
    return tmp_path


def test_nested_system_with_units_runs_with_converted_numbers(folder):
    (folder / "SystemStructure.ssd").write_text(NESTED)
    system = read_system(folder)
    assert [c.name for c in system.components] == ["deg_source", "celsius", "sub.feed", "sink"]
    assert sorted(map(str, system.connections)) == [
        "celsius.y -> sub.feed.u", "deg_source.y -> sub.feed.angle", "sub.feed.y -> sink.u"]
    assert system.inputs_without_source == ["sink.angle (through system connector "
                                            "'angle_ext')"]
    seen = {}
    with pytest.warns(UserWarning, match="sink.angle"):
        result = simulate_system(system, 1.0, 0.25, record=["sub.feed.*", "sink.*"],
                                 callback=lambda now, m: seen.setdefault(
                                     now, m.get("sub.feed.angle")))
    t = result["time"]
    assert seen[0.5] == result["sub.feed.angle"][2]  # nested names resolve in get/set
    assert_allclose(result["sub.feed.angle"], math.radians(90.0) * t, rtol=1e-15)  # deg->rad
    assert_allclose(result["sub.feed.u"], 20.0 + t + 273.15, rtol=1e-15)  # degC->K
    assert_allclose(result["sink.u"], 2.0 * (20.0 + t) + 1.0, rtol=1e-13)  # K->degC, 2x+1
    assert np.all(result["sink.angle"] == 0.0)  # no source: keeps its start value
    converted = result.meta["converted_connections"]
    assert converted["deg_source.y -> sub.feed.angle"] == [math.pi / 180.0, 0.0]
    assert_allclose(converted["sub.feed.y -> sink.u"], [2.0, 2.0 * -273.15 + 1.0])
    assert result.meta["inputs_without_source"] == system.inputs_without_source


@pytest.mark.parametrize("start_unit, end_connector, end_unit, message", [
    ("rad", "u", "degC", r"'rad' \(rad\) cannot be converted to 'degC' \(K\)"),
    ("degC", "angle", None, r"'degC' \(K\) cannot be converted to 'rad' \(rad\)"),  # FMU's rad
])
def test_incompatible_units_are_refused_naming_file_component_connector(
        folder, start_unit, end_connector, end_unit, message):
    ssd = HEAD + f"""<ssd:System name="top"><ssd:Elements>
      <ssd:Component name="source" source="Ramp.fmu">
        <ssd:Connectors>{real("y", "output", start_unit)}</ssd:Connectors></ssd:Component>
      <ssd:Component name="feed" source="Feed.fmu">
        <ssd:Connectors>{real(end_connector, "input", end_unit)}</ssd:Connectors>
      </ssd:Component></ssd:Elements>
      <ssd:Connections><ssd:Connection startElement="source" startConnector="y"
        endElement="feed" endConnector="{end_connector}"/></ssd:Connections></ssd:System>
    {UNITS}</ssd:SystemStructureDescription>"""
    (folder / "SystemStructure.ssd").write_text(ssd)
    with pytest.raises(IncompatibleConnectionError, match=message) as caught:
        Master(folder)
    error = caught.value
    assert error.file.endswith("SystemStructure.ssd")
    assert (error.component, error.variable) == ("feed", end_connector)


def test_start_value_in_another_unit_is_converted(folder):
    ssd = HEAD + """<ssd:System name="top"><ssd:Elements>
      <ssd:Component name="feed" source="Feed.fmu"><ssd:ParameterBindings>
        <ssd:ParameterBinding><ssd:ParameterValues><ssv:ParameterSet version="1.0" name="p">
        <ssv:Parameters><ssv:Parameter name="angle"><ssv:Real value="180" unit="deg"/>
        </ssv:Parameter></ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>
        </ssd:ParameterBinding></ssd:ParameterBindings></ssd:Component>
      </ssd:Elements></ssd:System>""" + UNITS + "</ssd:SystemStructureDescription>"
    (folder / "SystemStructure.ssd").write_text(ssd)
    with pytest.warns(UserWarning, match="feed.u"):
        result = simulate_system(folder, 0.25, 0.25, record=["feed.angle"])
    assert_allclose(result["feed.angle"], math.pi, rtol=1e-15)
    packed = _container_run(folder, "feed.angle")  # the container applies the converted start too
    assert_allclose(packed["feed.angle"], math.pi, rtol=1e-15)
    (folder / "SystemStructure.ssd").write_text(ssd.replace('unit="deg"', 'unit="degC"'))
    with pytest.raises(StartValueError, match=r"'degC' \(K\) cannot be converted to the "
                                              r"variable's unit 'rad'"):
        Master(folder)
    with pytest.raises(StartValueError, match="cannot be converted"):
        _container_run(folder, "feed.angle")


def _container_run(folder, name):
    from fmpy import simulate_fmu

    from orchestration.container import build_container_fmu

    fmu = build_container_fmu(read_system(folder / "SystemStructure.ssd"), folder / "packed.fmu", step_size=0.25)
    return simulate_fmu(str(fmu), stop_time=0.25, output_interval=0.25, output=[name])


def feed_copy(source, target, step: str):
    """Copy of the Feed FMU whose DefaultExperiment declares another stepSize."""
    with zipfile.ZipFile(source) as old, zipfile.ZipFile(target, "w") as new:
        for item in old.infolist():
            data = old.read(item)
            if item.filename == "modelDescription.xml":
                data = data.replace(b'stepSize="0.125"', f'stepSize="{step}"'.encode())
            new.writestr(item, data)
    return target


def test_step_falls_back_to_the_fmus_default_experiment(fixture_fmus, tmp_path):
    ramp_feed = System("rf", [Component("ramp", fixture_fmus["Ramp"]),
                              Component("feed", fixture_fmus["Feed"])],
                       [Connection.between("ramp.y", "feed.u")])
    with pytest.warns(DefaultStepWarning, match=r"using 0.125 s, the DefaultExperiment "
                                                r"stepSize of feed 0.125 s"):
        result = simulate_system(ramp_feed, 0.5, record=["feed.y"])
    assert_allclose(result["time"], [0.0, 0.125, 0.25, 0.375, 0.5])
    assert "DefaultExperiment" in result.meta["step_source"]
    fine = feed_copy(fixture_fmus["Feed"], tmp_path / "Feed.fmu", "0.0625")
    ramp_feed.components.append(Component("fine", fine))
    with pytest.warns(DefaultStepWarning, match=r"0.0625 s, the smallest DefaultExperiment "
                                                r"stepSize of the FMUs \(feed 0.125 s, fine "):
        assert simulate_system(ramp_feed, 0.5, record=["feed.y"]).size == 9
    alone = System("r", [Component("ramp", fixture_fmus["Ramp"])])
    with pytest.raises(ScheduleError, match="no communication step.*--step"):
        simulate_system(alone, 1.0)


def test_cosim_without_a_step_uses_the_default_experiment_and_says_so(fixture_fmus, tmp_path,
                                                                       capsys):
    path = write_ssp(System("f", [Component("feed", fixture_fmus["Feed"], {"u": 2.0})]),
                     tmp_path / "f.ssp")
    assert main(["cosim", str(path), "--stop-time", "0.5", "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "4 steps" in captured.out
    assert "sarins: warning: no communication step given and none in the system file: " \
           "using 0.125 s" in captured.err
    alone = write_ssp(System("r", [Component("ramp", fixture_fmus["Ramp"])]), tmp_path / "r.ssp")
    assert main(["cosim", str(alone), "--stop-time", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sarins cosim: error: no communication step")
    assert "Traceback" not in err


def test_units_and_transformations_survive_writing_a_flat_ssp(folder, tmp_path):
    ssd = HEAD + f"""<ssd:System name="top"><ssd:Elements>
      <ssd:Component name="source" source="Ramp.fmu">
        <ssd:Connectors>{real("y", "output", "deg")}</ssd:Connectors></ssd:Component>
      <ssd:Component name="feed" source="Feed.fmu"/></ssd:Elements>
      <ssd:Connections><ssd:Connection startElement="source" startConnector="y"
        endElement="feed" endConnector="angle"><ssc:LinearTransformation offset="1"/>
        </ssd:Connection></ssd:Connections></ssd:System>
    {UNITS}</ssd:SystemStructureDescription>"""
    (folder / "SystemStructure.ssd").write_text(ssd)
    system = read_system(folder)
    again = read_system(write_ssp(system, tmp_path / "again.ssp"))
    assert again.connections[0].hops[0].start_unit == "deg"
    with pytest.warns(UserWarning, match="feed.u"):
        first = simulate_system(system, 0.5, 0.25, record=["feed.angle"])
    with pytest.warns(UserWarning, match="feed.u"):
        second = simulate_system(again, 0.5, 0.25, record=["feed.angle"])
    assert_allclose(first["feed.angle"], math.radians(1.0) * first["time"] + 1.0, rtol=1e-15)
    assert_allclose(second["feed.angle"], first["feed.angle"], rtol=0, atol=0)
