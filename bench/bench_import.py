"""How long ``import snr`` takes, against a bare Python start-up.

Three commands, each in a fresh interpreter:

* ``python -c pass``: the baseline, Python starting and stopping;
* ``python -c "import snr"``;
* ``python -c "from snr import *"``.

The cases are interleaved (one run of each, then the next round), because the
machine's speed drifts, and each is run ``--runs`` times (at least 10). The
table shows the best and the median wall time, the overhead over the baseline
in milliseconds and the ratio to it. Bytecode caching is allowed and one
warm-up round fills the cache, as on a student's machine after the first run.
The interpreters run in the checkout this file is in, so they import its
``snr`` (``python -c`` puts the current directory first on ``sys.path``).

Run: ``python bench/bench_import.py [--runs N]`` (or ``nox -s bench``).
Add ``--importtime`` to see the 25 slowest modules behind ``import snr``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from typing import Dict, List, Tuple

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

CASES: List[Tuple[str, str]] = [
    ("python -c pass", "pass"),
    ('python -c "import snr"', "import snr"),
    ('python -c "from snr import *"', "from snr import *"),
]


def _env() -> Dict[str, str]:
    """The current environment with bytecode writing allowed."""
    return {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def run_once(code: str, env: Dict[str, str]) -> float:
    """Wall time in seconds of one fresh ``python -c code``."""
    started = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], check=True, env=env, cwd=ROOT)
    return time.perf_counter() - started


def measure(runs: int) -> Dict[str, List[float]]:
    """Every case ``runs`` times, interleaved, after one warm-up round."""
    env = _env()
    for _, code in CASES:
        run_once(code, env)
    times: Dict[str, List[float]] = {label: [] for label, _ in CASES}
    for _ in range(runs):
        for label, code in CASES:
            times[label].append(run_once(code, env))
    return times


def table(times: Dict[str, List[float]]) -> str:
    """The results as text: best and median, overhead in ms and ratio."""
    base_label = CASES[0][0]
    base_best = min(times[base_label])
    base_median = statistics.median(times[base_label])
    lines = [
        f"{'command':<32} {'best ms':>8} {'median ms':>10} "
        f"{'+ms best':>9} {'+ms median':>11} {'ratio':>6}"
    ]
    for label, _ in CASES:
        best = min(times[label])
        median = statistics.median(times[label])
        lines.append(
            f"{label:<32} {best * 1e3:>8.1f} {median * 1e3:>10.1f} "
            f"{(best - base_best) * 1e3:>9.1f} {(median - base_median) * 1e3:>11.1f} "
            f"{median / base_median:>6.2f}"
        )
    return "\n".join(lines)


def slowest_imports(count: int = 25) -> str:
    """The ``count`` modules with the largest cumulative ``-X importtime``."""
    result = subprocess.run(
        [sys.executable, "-X", "importtime", "-c", "import snr"],
        check=True,
        env=_env(),
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    rows: List[Tuple[int, str]] = []
    for line in result.stderr.splitlines():
        parts = line.split("|")
        if len(parts) == 3 and parts[1].strip().isdigit():
            rows.append((int(parts[1]), parts[2].rstrip()))
    rows.sort()
    return "\n".join(f"{us / 1e3:>8.1f} ms {name}" for us, name in rows[-count:])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=20, help="runs per command (at least 10)")
    parser.add_argument(
        "--importtime", action="store_true", help="also list the slowest modules imported"
    )
    args = parser.parse_args()
    runs = max(10, args.runs)
    times = measure(runs)
    print(f"\nImport time, {runs} fresh interpreters each (Python {sys.version.split()[0]})")
    print(table(times))
    if args.importtime:
        print("\nSlowest imports (cumulative, python -X importtime -c 'import snr'):")
        print(slowest_imports())


if __name__ == "__main__":
    main()
