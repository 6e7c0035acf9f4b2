"""The console's command table: what each command is called, how to type it, what it does.

`COMMANDS` is the one list of console commands: ``help`` and ``list
commands`` print it, `snr-console` completes command words from it, and
`CommandProcessorEndpoint` (``command_processor.py``) runs them.

Example::

    COMMANDS["dump"].usage     # 'dump profiler|datastore [KEY|PREFIX*]'
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict

from snr.std_mods.io.key_watch import (
    ECHO_DEFAULT_PAGES,
    ECHO_MAX_PAGES,
    HZ_DEFAULT_WINDOW_S,
    HZ_MAX_WINDOW_S,
)

__all__ = ["COMMANDS", "CommandHelp", "commands_table"]


@dataclass(frozen=True)
class CommandHelp:
    """How to type one command, and what it does (for ``help``).

    Example::

        CommandHelp("exit", "Stop the node and close this console.")
    """

    usage: str
    summary: str
    details: str = ""


COMMANDS: Dict[str, CommandHelp] = {
    "exit": CommandHelp("exit", "Stop the node and close this console."),
    "task": CommandHelp(
        "task <type> <name> [values...]",
        "Schedule a task on the node.",
        "Types: event, store_page (alias store_data), process_data, reload, terminate.\n"
        'Values are JSON where they parse (1, 2.5, true, null, "two words", [1, 2],\n'
        '{"k": 1}), otherwise plain words (A, hello). Examples:\n'
        "  task event button_pressed A\n"
        "  task store_page depth_m 3.2\n"
        "  task terminate done",
    ),
    "reload": CommandHelp(
        "reload all|<component>",
        "Reload a component's code from disk; its factory's state is kept.",
        "`reload all` reloads every component whose factory names modules to reload\n"
        "(super().__init__(my_module)). If the new code fails to load (a syntax error,\n"
        "an exception), the old version keeps running and the reply says why.",
    ),
    "list": CommandHelp(
        "list commands|endpoints", "List these commands, or the node's components."
    ),
    "dump": CommandHelp(
        "dump profiler|datastore [KEY|PREFIX*]",
        "Show handler timings, or the newest page of every key.",
        "`dump datastore` shows every key with a short preview of its value, up to the\n"
        "reply's limit. `dump datastore KEY` shows one key's value in full;\n"
        "`dump datastore PREFIX*` shows the keys that start with PREFIX.",
    ),
    "stats": CommandHelp(
        "stats",
        "Show the node's queue and every comms link: pages sent, received, dropped.",
        "Dropped pages are counted per link and per key (a slow peer whose backlog was\n"
        "full); 'heard' is how long ago the peer last sent anything (a beat at least).",
    ),
    "graph": CommandHelp(
        "graph [text|mermaid|dot]",
        "Show the node's components, the data keys each stores and handles, and its links.",
        "`text` (the default) is for reading here; `mermaid` can be pasted into a\n"
        "Markdown file (GitHub draws it), `dot` into Graphviz. Keys read but never\n"
        "stored, or stored but never read, are marked (!). `python -m snr graph main.py`\n"
        "draws the whole system without running it.",
    ),
    "echo": CommandHelp(
        "echo KEY [N]",
        "Show the next pages stored under KEY (snr-console repeats it until Ctrl-C).",
        f"One reply carries at most N pages (default {ECHO_DEFAULT_PAGES}, at most "
        f"{ECHO_MAX_PAGES}): it comes\nwhen N pages have come, a quarter second after the "
        "first, or after 1 s\nwithout one. Pages that come between two `echo KEY` wait "
        "for the next one,\nso repeating it shows every page.",
    ),
    "hz": CommandHelp(
        "hz KEY [WINDOW_S]",
        "Measure how often KEY is stored, and the jitter of the time between pages.",
        f"Counts pages for WINDOW_S seconds (default {HZ_DEFAULT_WINDOW_S:g}, at most "
        f"{HZ_MAX_WINDOW_S:g}), then replies with\nthe rate and the period's mean, min, max "
        "and standard deviation, timed when\nthis node stores each page.",
    ),
    "pause": CommandHelp(
        "pause",
        "Pause the node: it runs no task but the console's until `step` or `resume`.",
        "The node finishes the task it is running, then holds every other task in its\n"
        "queue, in order. dump, list, stats, graph and exit keep working. Loops keep\n"
        "running: their pages wait in the queue (a full queue makes them wait, then\n"
        "drops and counts their pages; the replies say how many).",
    ),
    "step": CommandHelp(
        "step [N]",
        "Run the next task (or N, at most 100) of a paused node and show what it did.",
        "For each task: which task ran, the handlers it went to, what they returned;\n"
        "then what waits next in the queue.",
    ),
    "resume": CommandHelp("resume", "Let a paused node run freely again."),
    "help": CommandHelp("help [command]", "Show the commands, or one command in detail."),
}
"""Every console command, in the order ``help`` lists them."""


def commands_table() -> str:
    """Every command's usage and summary, one aligned line each (``help``, ``list commands``).

    Example::

        print(commands_table())   #   exit    Stop the node and close this console. ...
    """
    width = max(len(entry.usage) for entry in COMMANDS.values())
    return "\n".join(f"  {e.usage:<{width}}  {e.summary}" for e in COMMANDS.values())
