"""The console's step mode: ``pause``, ``step [N]`` and ``resume`` (docs/console.md, "Step mode").

Registered with the kernel's `command` when a console starts, as ``echo``
and ``hz`` are; the step mode itself is the node's (``node.step_mode``,
``snr/core/checks/step_mode.py``): these commands only say what it did.

Example::

    127.0.0.1:9123> pause
    127.0.0.1:9123> step
    Ran (event, 'tick'): []
      went to: counter.on_tick
"""

from __future__ import annotations

from typing import List

from snr.core import Node
from snr.core.checks.step_mode import MAX_STEPS, Step
from snr.prelude import Task
from snr.prelude.task import format_task
from snr.std_mods.io.command_processor import (
    COMMANDS,
    Answer,
    CommandFailed,
    CommandProcessorEndpoint,
    command,
    no_arguments,
    number_argument,
)
from snr.std_mods.io.console_protocol import Reply, Status

__all__: List[str] = []


@command(
    "pause",
    "Pause the node: it runs no task but the console's until `step` or `resume`.",
    "The node finishes the task it is running, then holds every other task in its\n"
    "queue, in order. dump, list, stats, graph and exit keep working. Loops keep\n"
    "running: their pages wait in the queue (a full queue makes them wait, then\n"
    "drops and counts their pages; the replies say how many).",
)
def _pause(p: CommandProcessorEndpoint, args: str) -> Answer:
    no_arguments("pause", args)
    node = p.full_node("pause")
    if node.step_mode.paused:
        return f"Node {node.role!r} is already paused. {_loss_while_paused(node)}"
    node.step_mode.pause()
    return (
        f"Paused node {node.role!r}: its tasks wait in its queue (high-water mark "
        f"{node.queue.high_water:,}) until you step or resume.\n"
        f"{_next_line(node.step_mode.next_tasks(), len(node.queue))}\n"
        "Type `step` to run the next task, `resume` to let the node run on."
    )


@command(
    "step [N]",
    "Run the next task (or N, at most 100) of a paused node and show what it did.",
    "For each task: which task ran, the handlers it went to, what they returned;\n"
    "then what waits next in the queue.",
)
def _step(p: CommandProcessorEndpoint, args: str) -> Answer:
    words = args.split()
    if len(words) > 1:
        raise CommandFailed(f"Usage: {COMMANDS['step'].usage}, e.g. `step` or `step 5`.")
    count = int(number_argument(words[0], "step", "N", 1, MAX_STEPS, int)) if words else 1
    step_mode = p.full_node("step").step_mode
    if not step_mode.paused:
        raise CommandFailed(
            f"Node {p.parent.role!r} is running, so there is nothing to step: type `pause` first."
        )
    session = p.session
    if session is None:
        raise CommandFailed("`step` replies once its tasks ran: type it in a console.")
    try:
        step_mode.step(count, lambda steps: session.send(Reply(Status.OK, _steps_text(steps))))
    except ValueError as refused:
        raise CommandFailed(str(refused)) from None
    return None


@command("resume", "Let a paused node run freely again.")
def _resume(p: CommandProcessorEndpoint, args: str) -> Answer:
    no_arguments("resume", args)
    node = p.full_node("resume")
    if not node.step_mode.paused:
        return f"Node {node.role!r} is not paused."
    waiting = len(node.queue)
    lost = _loss_while_paused(node)
    node.step_mode.resume()
    plural = "s" if waiting != 1 else ""
    return f"Resumed node {node.role!r} with {waiting:,} task{plural} waiting. {lost}"


def _steps_text(steps: List[Step]) -> str:
    """What ``step`` did, task by task, and what waits next."""
    lines: List[str] = []
    for step in steps:
        if step.task is None:
            lines.append(
                "Nothing to step: no task waits. Tasks you schedule (`task ...`) and the "
                "pages of loops wait here while the node is paused."
            )
            continue
        lines.append(f"Ran {format_task(step.task, values='data')}")
        went_to = ", ".join(step.handlers) or "no handler (nothing handles this task)"
        lines.append(f"  went to: {went_to}")
        if step.returned:
            returned = ", ".join(format_task(t, values="data") for t in step.returned)
            lines.append(f"  returned: {returned}")
    if steps and steps[-1].task is not None:
        lines.append(_next_line(steps[-1].next_tasks, steps[-1].waiting))
    return "\n".join(lines)


def _loss_while_paused(node: Node) -> str:
    waits, dropped = node.step_mode.since_pause()
    return (
        f"Since the pause, loops waited for room in the queue {waits:,} times and "
        f"{dropped:,} of their tasks were dropped."
    )


def _next_line(next_tasks: List[Task], waiting: int) -> str:
    if not next_tasks:
        return "Next: nothing waits."
    plural = "s" if waiting != 1 else ""
    return f"Next: {format_task(next_tasks[0], values='data')} ({waiting:,} task{plural} waiting)"
