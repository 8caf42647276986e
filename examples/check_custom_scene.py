"""Check your own rig configuration from Python and read the verdict.

A scene is a TOML file: the linkage (lengths in mm) and what to check.  This one checks
only the crank's coupling plate at draft fidelity, so it runs in seconds.

Run: python examples/check_custom_scene.py [OUT_DIR]

Prints (tests/test_examples.py compares; ``...`` stands for what differs from run to run)::

    plate_A (original): peak 8.1 MPa = 2.2 % of the allowable 375 MPa, pass
    overall: pass - report in .../my-rig
"""

import sys
import tempfile
from pathlib import Path

from rigfem.pipeline import Output, Request, run_check

SCENE = """
description = "My four-bar: 480/840/780/1020 mm"

[linkage]
type = "four-bar"
b2 = 480.0
b3 = 840.0
b4 = 780.0
d = 1020.0
rails_mm = [700.0, 1000.0, 1000.0]

[check]
parts = ["plate_A"]
modes = ["original"]
fidelity = "draft"
frames = 0
"""

work = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
scene = work / "my-rig.toml"
scene.write_text(SCENE)
report = run_check(Request(scene), Output(work / "my-rig"))
for part in report["parts"]:
    print(f"{part['name']} ({part['mode']}): peak {part['peak_mpa']:.1f} MPa "
          f"= {part['utilisation_pct']:.1f} % of the allowable {part['limit_mpa']:.0f} MPa, "
          f"{part['verdict']}")
print("overall:", report["verdict"], "- report in", work / "my-rig")
