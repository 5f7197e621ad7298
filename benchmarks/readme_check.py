"""Rerun the README's campaign figures and fail when one drifts beyond its tolerance (``make readme-check``).

Runs ``benchmarks/bench_campaign.py`` (synth → run → learn → predict, seed 0) and compares what it prints with the
README's campaign table: identification medians within ±30 % (relative) or 0.05 points, interval coverage within
±5 points, ANFIS / GP metrics within ±15 % relative, FRF errors within ±0.3 points. Times are not checked (they
depend on the machine's load). Table 1 is checked by ``tests/base/test_readme.py`` (slow tier).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _num(text: str) -> float:
    return float(text.replace("%", "").strip())


def main() -> int:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    with tempfile.TemporaryDirectory() as d:
        out = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "bench_campaign.py"), "--workdir", d],
                             capture_output=True, text=True, check=True).stdout
    print(out)
    bad = []

    def check(name, measured, shown, rel=None, abs_=None):
        ok = (rel is not None and abs(measured - shown) <= rel * abs(shown)) or \
             (abs_ is not None and abs(measured - shown) <= abs_)
        print(f"{'ok ' if ok else 'BAD'} {name}: README {shown:g}, now {measured:g}")
        if not ok:
            bad.append(name)

    med = dict(re.findall(r"^\s+(kt|ct|kr|cr):\s+([\d.]+) %\s+/", out, re.M)[:4])
    row = re.search(r"median \(all 178\) \| kt ([\d.]+) %, ct ([\d.]+) %, kr ([\d.]+) %, cr ([\d.]+) %", readme)
    for k, shown in zip(("kt", "ct", "kr", "cr"), row.groups()):
        check(f"identified median {k}", float(med[k]), float(shown), rel=0.3, abs_=0.05)
    cov = dict(re.findall(r"^\s+(kt|ct|kr|cr):.*truth inside 95 % CI: (\d+)%", out, re.M))
    row = re.search(r"intervals \(all 178\) \| kt (\d+) %, ct (\d+) %, kr (\d+) %, cr (\d+) %", readme)
    for k, shown in zip(("kt", "ct", "kr", "cr"), row.groups()):
        check(f"coverage {k}", float(cov[k]), float(shown), abs_=5)
    kt = re.search(r"^kt \[N/m\].*?^ANFIS\s+test\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)", out, re.M | re.S).groups()
    row = re.search(r"NRMSE ([\d.]+), AFV ([\d.]+), MAPE ([\d.]+) %, max APE ([\d.]+) %", readme).groups()
    for name, m, r in zip(("kt NRMSE", "kt AFV", "kt MAPE", "kt max APE"), kt, row):
        check(f"ANFIS {name}", float(m), float(r), rel=0.15)
    gp = re.search(r"^kt \[N/m\].*?^GP regression\s+test\s+\d+\s+(\S+)\s+\S+\s+(\S+)", out, re.M | re.S).groups()
    row = re.search(r"GP baseline kt, test \| NRMSE ([\d.]+), MAPE ([\d.]+) %", readme).groups()
    for name, m, r in zip(("NRMSE", "MAPE"), gp, row):
        check(f"GP kt {name}", float(m), float(r), rel=0.15)
    kr = re.search(r"^kr \[N m/rad\].*?^ANFIS\s+test\s+\d+\s+\S+\s+\S+\s+(\S+)", out, re.M | re.S).group(1)
    check("ANFIS kr MAPE", float(kr), float(re.search(r"identified\) \| MAPE ([\d.]+) %", readme).group(1)), rel=0.15)
    f = re.search(r"frequency error: median ([\d.]+) %, max ([\d.]+) %", out).groups()
    m = re.search(r"magnitude error: median ([\d.]+) %, max ([\d.]+) %", out).groups()
    rf = re.search(r"dominant-peak frequency error \| median ([\d.]+) %, max ([\d.]+) %", readme).groups()
    rm = re.search(r"dominant-peak magnitude error \| median ([\d.]+) %, max ([\d.]+) %", readme).groups()
    for name, a, b in zip(("peak f median", "peak f max", "peak |H| median", "peak |H| max"), f + m, rf + rm):
        check(name, float(a), float(b), abs_=0.3 if "f" in name.split()[1] else 2.0)
    print(f"{len(bad)} README figures drifted" + (f": {', '.join(bad)}" if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
