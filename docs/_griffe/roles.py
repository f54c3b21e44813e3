"""A griffe extension for the API pages: reST cross-reference roles become links.

The package's docstrings name other objects the Sphinx way (:func:`run`,
:class:`~gpmotion.task.Task`, :mod:`gpmotion.sim`), which Markdown would show as
plain text.  Each role becomes an optional autoref: a link when the target is
rendered somewhere on the site, inline code otherwise (never a broken link, so
``mkdocs build --strict`` stays green).  A short name resolves the way Python
would read it in the docstring's own scope: the class, then the module, each
imported name followed to what it names.
"""
from __future__ import annotations

import html
import re

import griffe

ROLE = re.compile(r":(?:py:)?(?:class|func|meth|mod|data|attr|exc|obj):`(?P<body>[^`]+)`")


def _scopes(obj):
    """The object and its parents up to the module: where a short name may live."""
    while obj is not None:
        yield obj
        if obj.is_module:
            return
        obj = obj.parent


def resolve(obj, target: str) -> str:
    """The full dotted path ``target`` names as written in ``obj``'s docstring."""
    first, _, rest = target.lstrip(".").partition(".")
    for scope in _scopes(obj):
        member = scope.members.get(first) if hasattr(scope, "members") else None
        if member is not None:
            base = member.target_path if member.is_alias else member.path
            return f"{base}.{rest}" if rest else base
    return target.lstrip(".")


def markdown_role(obj, body: str) -> str:
    """One role's Markdown: an optional autoref around the code-formatted title."""
    explicit = re.fullmatch(r"(?P<title>.+?)\s*<(?P<target>[^>]+)>", body)
    if explicit:
        title, target = explicit["title"], explicit["target"]
    else:
        target = body.lstrip("~")
        title = target.rsplit(".", 1)[-1] if body.startswith("~") else target.lstrip(".")
    path = resolve(obj, target.lstrip("~"))
    return (f'<autoref identifier="{html.escape(path, quote=True)}" optional>'
            f"<code>{html.escape(title)}</code></autoref>")


def convert(obj, text: str) -> str:
    return ROLE.sub(lambda m: markdown_role(obj, m["body"]), text)


def _walk(obj, seen):
    if obj.path in seen:
        return
    seen.add(obj.path)
    if obj.docstring is not None:
        obj.docstring.value = convert(obj, obj.docstring.value)
    for member in obj.members.values():
        if not member.is_alias:
            _walk(member, seen)


class SphinxRoles(griffe.Extension):
    """Rewrites every docstring of a loaded package once the whole package is known."""

    def on_package(self, *, pkg, **kwargs) -> None:
        _walk(pkg, set())
