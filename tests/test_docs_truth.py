"""The documents say what the code does: numbers written by a script are checked against a fresh run."""

import argparse
import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def _engine_table():
    spec = importlib.util.spec_from_file_location("engine_table", ROOT / "benchmarks" / "engine_table.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("row", ["| `standard_static` (7000 s)", "| `standard_static_identified`",
                                 "| `vehicle_rins` (2900 s)", "| `vehicle_rins_online`"])
def test_the_readme_engine_table_holds_the_masters_numbers(row, fmu_dir):
    """``python benchmarks/engine_table.py --write-readme`` wrote them; a fresh Gauss-Seidel run gives them."""
    table = _engine_table()
    name, unit = table.README_ROW[row]
    (line,) = [line for line in README.read_text(encoding="utf-8").splitlines() if line.startswith(row)]
    assert line.split(" | ")[1] == table.readme_value(table.reference_values(name, fmu_dir), unit)


def test_the_readme_and_build_fmus_help_say_which_fmus_are_native():
    """The README's FMU table and ``sarins build-fmus --help`` name the native FMUs as the build makes
    them (every FMU) (fmus.native_fmu.NATIVE)."""
    from fmus import SLAVES
    from fmus.native_fmu import NATIVE
    from sarins.cli import build_fmus as command

    rows = {line.split("|")[1].strip(" `"): line.split("|")[3].strip() for line in README.read_text().splitlines()
            if line.startswith("| `") and line.count("|") == 4}
    assert {n: rows[n] for n in SLAVES} == {n: "native C" if n in NATIVE else "Python-hosted" for n in SLAVES}
    sub = argparse.ArgumentParser().add_subparsers()
    command.register(sub)
    text = " ".join(sub.choices["build-fmus"].description.split())
    native_part = text.split("the native C FMUs ")[1].split(" every FMI call in C")[0]
    assert all(n in native_part for n in NATIVE) and set(SLAVES) == set(NATIVE)


def test_the_docs_cite_no_missing_file():
    assert "FACTS.md" not in (ROOT / "tests" / "test_native_fmus3_sub.py").read_text()


DOCS = [README, *sorted((ROOT / "docs").glob("*.md"))]


def _command_texts(text):
    """The lines of fenced code blocks (continuation lines joined) and the inline code spans of a document."""
    for block in re.findall(r"```[^\n]*\n(.*?)```", text, flags=re.S):
        yield from block.replace("\\\n", " ").splitlines()
    yield from re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S))


def _subcommands(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return action.choices
    return {}


def _documented_options():
    """(document, command words, option) for every ``sarins <command> [<sub-command>] ... --option`` in the docs."""
    for doc in DOCS:
        for text in _command_texts(doc.read_text(encoding="utf-8")):
            for match in re.finditer(r"\bsarins ([a-z][a-z0-9-]*)(.*)", text):
                words = match.group(2).split()
                for word in words:
                    if word.startswith("--"):
                        yield doc.name, match.group(1), words[0] if words else "", word.split("=")[0].rstrip(",.;:)]")


def test_every_option_the_docs_give_a_command_exists_in_its_parser():
    """``sarins navigate --write-log PATH`` in a document means ``--write-log`` is an option of
    ``sarins navigate`` (of ``sarins campaign <name>`` for a campaign)."""
    from sarins.cli import build_parser

    commands = _subcommands(build_parser())
    found = list(_documented_options())
    assert len(found) > 50  # the docs name options of every command; a regex that finds none checks nothing
    missing = []
    for doc, name, first, option in found:
        parser = commands.get(name)
        if parser is None:
            missing.append((doc, name, option))
            continue
        parser = _subcommands(parser).get(first, parser)
        if option not in {string for action in parser._actions for string in action.option_strings}:
            missing.append((doc, f"{name} {first}".strip(), option))
    assert missing == []


def test_every_repository_path_the_docs_name_exists():
    """A path in a code span that starts at a top-level folder of the repository (``fmus/native/...``), and
    every relative Markdown link, names a file or folder that exists; ``build/`` holds outputs and is skipped."""
    tops = tuple(p.name + "/" for p in ROOT.iterdir() if p.is_dir() and p.name not in {"build"}
                 and not p.name.startswith("."))
    checked, missing = 0, []
    for doc in DOCS:
        text = doc.read_text(encoding="utf-8")
        for span in re.findall(r"`([^`\n]+)`", text):
            for word in span.split():
                path = word.rstrip(",.;:)]").split("::")[0]
                if path.startswith(tops) and not any(c in path for c in "*<>{}$"):
                    checked += 1
                    if not (ROOT / path).exists():
                        missing.append((doc.name, path))
        for target in re.findall(r"\]\(([^)#\s]+)", text):
            if "://" not in target:
                checked += 1
                if not (doc.parent / target).exists():
                    missing.append((doc.name, target))
    assert checked > 100
    assert missing == []


def test_the_docs_speak_of_the_product_not_of_issue_numbers():
    """"issue 20 item 5" says when something changed, which is CHANGELOG.md's business; an outside
    project's issue ("Fusion issue #191") is a citation and stays."""
    cited = [(doc.name, number) for doc in DOCS
             for number in re.findall(r"\b[Ii]ssues? (\d+)", doc.read_text(encoding="utf-8"))]
    assert cited == []
