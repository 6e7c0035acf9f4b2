"""Lesson 4's grader: does the filter remove the noise, without lagging behind?

It replays `SAMPLES` noisy readings (`make_signal`, seed 42) into the
student's endpoint, in one node in simulated time, and checks the ``depth``
pages it stores against the true depth, never the code's names:

* it runs without an exception;
* it stores a ``depth`` number for (nearly) every ``depth_raw`` page;
* their RMS error is at most `NOISE_FRACTION` of the readings';
* they lag the true depth by at most `MOST_LAG` samples.

The first `WARM_UP` samples are not measured: a filter may start slowly.

Example::

    for check in grade(Path("depth_filter.py")):
        print(check.passed, check.name)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Dict, List

from snr.extras.lessons.grading import (
    Check,
    find_endpoint,
    first_checks,
    handler_line,
    load_submission,
    replay,
)
from snr.extras.lessons.l04_depth_filter.solution import (
    RATE_HZ,
    make_signal,
    rms_error,
)

__all__ = [
    "KEYS",
    "MOST_LAG",
    "NOISE_FRACTION",
    "PAGES_FRACTION",
    "SAMPLES",
    "WARM_UP",
    "grade",
]

KEYS = ["depth_raw"]
"""The pages the endpoint handles."""
SAMPLES = 400
"""Readings replayed: two waves, 8 s at 50 a second."""
WARM_UP = 20
"""The first readings, not measured."""
PAGES_FRACTION = 0.95
"""At least this share of the measured readings must get a ``depth`` page."""
NOISE_FRACTION = 0.5
"""The filtered RMS error must be at most this share of the readings' own."""
MOST_LAG = 10
"""The filtered depth may lag the true one by this many samples at most (0.2 s)."""
SEARCHED_LAG = 20
"""The lags tried, 0 to this: a lag of this means this or more."""


def grade(path: Path) -> List[Check]:
    """The checks of lesson 4 for the student's file at ``path``.

    Raises:
        SubmissionError: the file cannot be loaded, or has no endpoint.

    Example::

        all(check.passed for check in grade(Path("depth_filter.py")))
    """
    cls = find_endpoint(load_submission(path), KEYS)
    clean, raw = make_signal(SAMPLES)
    run, endpoint = replay(cls, path, raw, "depth_raw", "depth")
    smooth = handler_line(endpoint, "depth_raw")
    checks = first_checks(cls, endpoint, "depth_raw", run.error)
    if run.error is not None:
        return checks
    # Each answer, by the reading it answers (the last, if several).
    depth: Dict[int, float] = {}
    not_numbers = []
    for inputs, data in run.outputs:
        if isinstance(data, (int, float)) and not isinstance(data, bool) and math.isfinite(data):
            depth[inputs - 1] = float(data)
        else:
            not_numbers.append(data)
    measured = [i for i in range(WARM_UP, SAMPLES) if i in depth]
    wanted = math.ceil(PAGES_FRACTION * (SAMPLES - WARM_UP))
    odd = f"; {len(not_numbers)} not a number, e.g. {not_numbers[0]!r}" if not_numbers else ""
    checks.append(
        Check(
            "stores a depth page for each reading",
            len(measured) >= wanted,
            expected=f"a 'depth' page (a number) for at least {wanted} of the "
            f"{SAMPLES - WARM_UP} 'depth_raw' pages after the first {WARM_UP}",
            happened=f"{len(run.outputs)} 'depth' pages for {run.inputs} 'depth_raw' pages{odd}",
            hint='return self.store_data_task("depth", a number) from the handler, '
            "for every reading (step 1)",
            line=smooth,
        )
    )
    if not measured:
        return checks
    filtered = [depth[i] for i in measured]
    truth = [clean[i] for i in measured]
    raw_error = rms_error([raw[i] for i in measured], truth)
    error = rms_error(filtered, truth)
    checks.append(
        Check(
            "removes the noise",
            error <= NOISE_FRACTION * raw_error,
            expected=f"an RMS error against the true depth at most {NOISE_FRACTION:g} x the "
            f"readings' ({raw_error:.3f} m): {NOISE_FRACTION * raw_error:.3f} m",
            happened=f"{error:.3f} m, {error / raw_error:.2f} x the readings'",
            hint="store the mean of the last WINDOW readings, not the reading (step 2)",
            line=smooth,
        )
    )
    # The lag: the shift of the true depth that the filtered depth is nearest
    # (`lag_samples`, on the measured readings only). WARM_UP >= SEARCHED_LAG.
    lag = min(
        range(SEARCHED_LAG + 1),
        key=lambda shift: rms_error(filtered, [clean[i - shift] for i in measured]),
    )
    said = f"{lag} samples" + (" or more" if lag == SEARCHED_LAG else "")
    checks.append(
        Check(
            "keeps up with the depth",
            lag <= MOST_LAG,
            expected=f"at most {MOST_LAG} samples ({MOST_LAG / RATE_HZ:g} s) behind the true depth",
            happened=f"{said} ({lag / RATE_HZ:g} s) behind",
            hint="a shorter window lags less: the mean of N readings lags (N - 1) / 2 (step 3)",
            line=smooth,
        )
    )
    return checks
