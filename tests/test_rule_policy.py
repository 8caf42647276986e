"""Issue 24 §7: one rule for a rig configuration that breaks a rig rule, the same for every
command that takes one: the commands that judge strength (check, verify, convergence) refuse it
(exit 2) unless --allow-rule-violations; the ones that only describe it (reactions, kinematics)
compute it; all show the broken rule as the first line and in --json / every report."""

from __future__ import annotations

import json
import re

import pytest

from rigfem.cli import main
from rigfem.cli.exitcodes import RULES_REFUSED, RULES_SHOWN

BROKEN = "final-nc"     # transmission angle 34.2–148.7°, outside the rig's 35–145° band
FAST = ["--parts", "plate_A", "--modes", "original", "--fidelity", "draft", "--frames", "0", "--quiet"]


def _help(command: str, capsys) -> str:
    with pytest.raises(SystemExit):
        main([command, "--help"])
    return "".join(capsys.readouterr().out.split())   # argparse wraps lines, also at hyphens


@pytest.mark.parametrize("command,rule", [("check", RULES_REFUSED), ("verify", RULES_REFUSED),
                                          ("convergence", RULES_REFUSED), ("reactions", RULES_SHOWN),
                                          ("kinematics", RULES_SHOWN)])
def test_every_command_documents_the_rule_in_its_help(command, rule, capsys):
    assert "".join(rule.split()) in _help(command, capsys)


@pytest.mark.parametrize("argv", [["verify", BROKEN], ["convergence", BROKEN, "--out", "{tmp}/cv"],
                                  ["check", BROKEN, "--out", "{tmp}/ck"]])
def test_judging_commands_refuse_a_broken_rule_before_any_work(argv, tmp_path, capsys):
    assert main([a.format(tmp=tmp_path) for a in argv]) == 2
    err = capsys.readouterr().err
    assert "breaks the rig rule transmission angle min" in err and "--allow-rule-violations" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["reactions", "kinematics"])
def test_describing_commands_show_the_broken_rule_first(command, capsys):
    assert main([command, BROKEN]) == 0
    assert capsys.readouterr().out.splitlines()[0].startswith("WARNING: breaks rig rule transmission angle")
    assert main([command, BROKEN, "--json"]) == 0
    assert any("transmission angle" in v for v in json.loads(capsys.readouterr().out)["rule_violations"])
    assert main([command, "final-cm", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["rule_violations"] == []


def test_allowed_check_shows_the_broken_rule_first_and_fails(tmp_path, capsys):
    out = tmp_path / "ck"
    assert main(["check", BROKEN, "--allow-rule-violations", "--out", str(out), *FAST]) == 1
    assert re.match(r"WARNING: breaks rig rule transmission angle min", capsys.readouterr().out)
    broken = json.loads((out / "report.json").read_text())["rule_violations"]
    assert broken
    for command in ("reactions", "kinematics"):   # one message per rule, the same in every command
        assert main([command, BROKEN, "--json"]) == 0
        assert json.loads(capsys.readouterr().out)["rule_violations"] == broken


def test_describing_commands_name_every_broken_rule_not_only_the_transmission_angle(capsys):
    argv = ["--four-bar", "480", "840", "780", "610"]   # ground below the 660 mm the crank guide needs
    for command in ("reactions", "kinematics"):
        assert main([command, *argv, "--json"]) == 0
        assert any(v.startswith("crank guide clears the rocker pivot")
                   for v in json.loads(capsys.readouterr().out)["rule_violations"])
