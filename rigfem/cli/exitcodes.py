"""Exit codes of the ``rigfem`` command: the CLI is the only place that knows them.

0 every part passes; 1 a part fails or cannot be decided; 2 bad input; 3 could not compute
(mesher, solver, an external program or an internal error); 130 interrupted (Ctrl-C);
143 terminated (SIGTERM); 141 the reader of the output went away (``rigfem ... | head``).
"""

from __future__ import annotations

PASS, FAIL, BAD_INPUT, NO_COMPUTE = 0, 1, 2, 3
INTERRUPTED, TERMINATED, PIPE_CLOSED = 130, 143, 141

#: verdict of a check -> exit code
EXIT = {"pass": PASS, "fail": FAIL, "undecided": FAIL}



def table(success: str | None = None) -> str:
    """The exit codes of a command, for its ``--help``: a check's verdict codes (0, 1), or, for a
    command that has no verdict, 0 with its ``success`` meaning (no 1)."""
    first = (f"0 {success}" if success else
             "0 every part passes, 1 a part fails or cannot be decided")
    return (f"exit codes: {first}, 2 bad input, 3 could not compute (mesher, solver or internal error), "
            "130 Ctrl-C, 143 SIGTERM, 141 output pipe closed")


#: the one rule for a rig configuration that breaks a rig rule, by kind of command (README "Exit codes")
RULES_REFUSED = ("a rig configuration that breaks a rig rule is refused (exit 2, naming the rule) unless "
                 "--allow-rule-violations; then 'WARNING: breaks rig rule …' is the first line, every report "
                 "lists rule_violations and a check's verdict is FAIL")
RULES_SHOWN = ("a rig configuration that breaks a rig rule is computed (no verdict: exit 0) with 'WARNING: breaks "
               "rig rule …' as the first line and rule_violations in --json; rigfem check refuses it (exit 2)")

#: the table printed by ``rigfem --help`` and README
TABLE = table()
