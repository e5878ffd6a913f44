"""The FMU reference's variable table (docs/fmu.md, "Variables") states exactly what the packaged
modelDescription.xml says."""
import re
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_readme_variable_table_matches_the_model_description(fmu_path):
    root = ET.fromstring(zipfile.ZipFile(fmu_path).read("modelDescription.xml"))
    described = {}
    for sv in root.iter("ScalarVariable"):
        t = list(sv)[0]
        described[sv.get("name")] = (sv.get("valueReference"), sv.get("causality"), t.tag, t.get("unit", ""))
    rows = re.findall(r"^\| `([^`]+)` \| (\d+) \| (\w+) \| (\w+) \| [^|]* \| ([^|]*) \|", (ROOT / "docs" / "fmu.md").read_text(), re.M)
    documented = {name: (vr, causality, ty, unit.strip()) for name, vr, causality, ty, unit in rows}
    assert documented == described
