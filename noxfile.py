"""Developer sessions: ``nox -s tests``, ``compat``, ``mypy``, ``lint``, ``bench``, ``docs``."""

from __future__ import annotations

import nox

nox.options.sessions = ["tests", "mypy", "lint"]


@nox.session
def tests(session: nox.Session) -> None:
    """Run the test suite."""
    session.install("-e", ".[dev]")
    session.run("python", "-m", "pytest", *session.posargs)


@nox.session(python=["3.9", "3.10", "3.11", "3.12", "3.13"])
def compat(session: nox.Session) -> None:
    """Run the test suite on every supported Python that is installed."""
    session.install("-e", ".[dev]")
    session.run("python", "-m", "pytest", *session.posargs)


@nox.session
def mypy(session: nox.Session) -> None:
    """Type-check the library, the examples and the tests strictly."""
    session.install("-e", ".[dev]")
    session.run("python", "-m", "mypy", "--strict", "snr", "examples", "tests")


@nox.session
def lint(session: nox.Session) -> None:
    """Lint with ruff."""
    session.install("ruff")
    session.run("ruff", "check", "snr", "tests", "examples", "bench")
    session.run("ruff", "format", "--check", "snr", "tests", "examples", "bench")


@nox.session
def bench(session: nox.Session) -> None:
    """Run every benchmark in bench/ and print their tables."""
    session.install("-e", ".[dev]")
    for script in sorted(__import__("glob").glob("bench/bench_*.py")):
        session.run("python", script, *session.posargs)


@nox.session
def docs(session: nox.Session) -> None:
    """Build the API reference and the guide into docs/api/; fail on any warning."""
    session.install("-e", ".[dev]")
    session.run("python", "-m", "snr", "docs", "--build-only", *session.posargs)
