"""The command-line reference as Markdown, generated from the argument parser.

``python -m gpmotion.cli.reference > docs/reference/cli.md`` writes the page the
documentation site publishes; a test checks that the committed page equals this
module's output, so the reference cannot drift from the parser.
"""
from __future__ import annotations

import argparse
import sys

# Usage lines are wrapped at a fixed width so the page does not depend on the terminal.
WIDTH = 88

# Commands whose options live in a parser of their own (the subparser only forwards argv).
DELEGATED = {"bench": ("gpmotion.bench", "build_parser")}

HEADER = """# Command-line reference

Generated from the argument parser by `python -m gpmotion.cli.reference`;
do not edit by hand. `gpmotion help COMMAND` prints the same text in a terminal.
"""


def markdown(ap: argparse.ArgumentParser | None = None) -> str:
    """The whole reference page for ``gpmotion.cli.parser()`` (or ``ap``)."""
    if ap is None:
        from . import parser
        ap = parser()
    parts = [HEADER, _section(ap, "gpmotion", level=2)]
    for name, sub in _subcommands(ap):
        parts.append(_command(name, sub, level=2))
    return "\n".join(parts).rstrip() + "\n"


def _command(name: str, sub: argparse.ArgumentParser, level: int) -> str:
    if name.split()[-1] in DELEGATED and not _visible_actions(sub):
        module, function = DELEGATED[name.split()[-1]]
        sub = getattr(__import__(module, fromlist=[function]), function)()
    parts = [_section(sub, name, level)]
    for child, subsub in _subcommands(sub):
        parts.append(_command(child, subsub, level + 1))
    return "\n".join(parts)


def _subcommands(ap: argparse.ArgumentParser):
    for action in ap._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {c.dest: c.help for c in action._choices_actions}
            for name, sub in action.choices.items():
                sub._reference_help = helps.get(name)
                yield sub.prog.removeprefix("gpmotion "), sub


def _section(ap: argparse.ArgumentParser, name: str, level: int) -> str:
    title = "gpmotion" if name == "gpmotion" else f"gpmotion {name}"
    lines = [f"{'#' * level} `{title}`", ""]
    summary = getattr(ap, "_reference_help", None) or ap.description
    if summary:
        lines += [_inline(summary), ""]
    fmt = argparse.HelpFormatter(prog=title, width=WIDTH)
    fmt.add_usage(ap.usage, ap._actions, ap._mutually_exclusive_groups, prefix="")
    lines += ["```text", fmt.format_help().strip(), "```", ""]
    for group in ap._action_groups:
        rows = [_row(fmt, a) for a in group._group_actions if _shown(a)]
        if not rows:
            continue
        lines += [f"**{_inline(group.title or 'options')}**", ""]
        if group.description:
            lines += [_inline(group.description), ""]
        lines += ["| argument | meaning |", "|---|---|", *rows, ""]
    if ap.epilog and name != "gpmotion":
        lines += ["```text", ap.epilog.strip(), "```", ""]
    return "\n".join(lines)


def _shown(action: argparse.Action) -> bool:
    return action.help is not argparse.SUPPRESS and not isinstance(
        action, (argparse._HelpAction, argparse._SubParsersAction))


def _visible_actions(ap: argparse.ArgumentParser) -> list:
    return [a for a in ap._actions if _shown(a)]


def _row(fmt: argparse.HelpFormatter, action: argparse.Action) -> str:
    if action.option_strings:
        flags = ", ".join(action.option_strings)
        if action.nargs != 0:
            flags += " " + fmt._format_args(action, fmt._get_default_metavar_for_optional(action))
    else:
        flags = action.metavar or action.dest
    meaning = fmt._expand_help(action) if action.help else ""
    if action.choices is not None and not isinstance(action.choices, dict):
        meaning += f" (one of: {', '.join(map(str, action.choices))})"
    return f"| `{flags}` | {_cell(meaning)} |"


def _inline(text: str) -> str:
    return " ".join(text.split()).replace("<", "&lt;").replace(">", "&gt;")


def _cell(text: str) -> str:
    return _inline(text).replace("|", "\\|")


def main(argv=None) -> int:
    sys.stdout.write(markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
