"""The ``meshladar-cli`` directive: the command line's reference, made from its argparse
parser when the site is built, so it cannot drift from ``meshladar COMMAND --help``.

Each command becomes a section: its description, its usage line, and per argument group a
definition list of the arguments (flags, metavar, help with its default filled in).
"""

from __future__ import annotations

import argparse

from docutils import nodes
from docutils.parsers.rst import Directive

from meshladar.cli import COMMANDS
from meshladar.cli.parser import build_parser


def _help(action, parser):
    text = action.help or ""
    if "%(" in text:
        text = text % {**vars(action), "prog": parser.prog,
                       "default": action.default}
    return text


def _term(action):
    if not action.option_strings:
        return action.metavar or action.dest
    flags = ", ".join(action.option_strings)
    if action.nargs == 0:
        return flags
    meta = action.metavar or action.dest.upper()
    return f"{flags} {' '.join(meta) if isinstance(meta, tuple) else meta}"


def _arguments(actions, parser):
    items = nodes.definition_list()
    for action in actions:
        if isinstance(action, argparse._HelpAction) or action.help == argparse.SUPPRESS:
            continue
        item = nodes.definition_list_item()
        term = nodes.term()
        term += nodes.literal(text=_term(action))       # as typed: no smart dashes
        item += term
        body = nodes.definition()
        body += nodes.paragraph(text=_help(action, parser))
        item += body
        items += item
    return items


def _command(name, parser, document):
    section = nodes.section(ids=[f"command-{name}"], names=[f"meshladar {name}"])
    section += nodes.title(text=f"meshladar {name}")
    if parser.description:
        section += nodes.paragraph(text=parser.description)
    section += nodes.literal_block(text=parser.format_usage().strip())
    for group in parser._action_groups:
        actions = [a for a in group._group_actions
                   if not isinstance(a, argparse._HelpAction)]
        if not actions:
            continue
        section += nodes.rubric(text=group.title)
        section += _arguments(actions, parser)
    if parser.epilog:
        section += nodes.literal_block(text=parser.epilog.strip())
    return section


class CliReference(Directive):
    """``.. meshladar-cli::``: one section per command, in the parser's order."""

    has_content = False

    def run(self):
        parser = build_parser(COMMANDS)
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        return [_command(name, p, self.state.document) for name, p in sub.choices.items()]


def setup(app):
    app.add_directive("meshladar-cli", CliReference)
    return {"parallel_read_safe": True, "version": "1"}
