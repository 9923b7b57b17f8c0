"""Render the reproduction report from its template and the generated figures and tables.

The template ``paper/paper.md`` holds the prose; placeholders pull in what the notebooks made,
so a number in the report is always the one the code produced:

- ``{{table:NAME}}``: the Markdown table ``paper/generated/NAME.md``;
- ``{{figure:NAME|caption}}``: the image ``figures/NAME.png``;
- ``{{number:NAME.key.subkey|fmt}}``: a value from ``paper/generated/NAME.json`` (``fmt`` e.g. ``.4f``).

The result is ``paper/generated/paper.md``. A placeholder whose file is missing renders as a
visible "not generated" note, and :func:`build_paper` lists them.
"""
from __future__ import annotations

import json
import os
import re
from pathlib import Path

from crfmap import paths
from crfmap.io.atomic import atomic_path

PLACEHOLDER = re.compile(r"\{\{(table|figure|number):([^}|]+)(?:\|([^}]*))?\}\}")


def _relative(target: Path, start: Path) -> str:
    return Path(os.path.relpath(target, start)).as_posix()


def render(template: str, out_dir: Path, missing: list) -> str:
    def replace(match):
        kind, name, extra = match.group(1), match.group(2).strip(), match.group(3)
        if kind == "table":
            f = paths.GENERATED / f"{name}.md"
            if not f.exists():
                missing.append(f"table {name}")
                return f"*(table {name} not generated)*"
            return f.read_text().rstrip("\n")
        if kind == "figure":
            f = paths.FIGURES / f"{name}.png"
            if not f.exists():
                missing.append(f"figure {name}")
                return f"*(figure {name} not generated)*"
            caption = extra or name
            return f"![{caption}]({_relative(f, out_dir)})"
        file_name, *keys = name.split(".")
        f = paths.GENERATED / f"{file_name}.json"
        try:
            value = json.loads(f.read_text())
            for k in keys:
                value = value[int(k)] if isinstance(value, list) else value[k]
        except (OSError, KeyError, IndexError, ValueError):
            missing.append(f"number {name}")
            return f"*(number {name} not generated)*"
        if value is None:
            return "n/a"
        return format(value, extra) if extra else str(value)

    return PLACEHOLDER.sub(replace, template)


def build_paper(template: Path | None = None, output: Path | None = None, publish: bool = True) -> Path:
    """Render the template into ``paper/generated/paper.md``; returns its path.

    ``publish=True`` also builds ``paper.pdf`` and ``paper.html`` beside it (:mod:`crfmap.repro.publish`).
    """
    template = Path(template or paths.PAPER / "paper.md")
    output = Path(output or paths.GENERATED / "paper.md")
    missing: list = []
    text = render(template.read_text(), output.parent, missing)
    if missing:
        text += "\n\n---\nNot generated when this report was built: " + ", ".join(missing) + "\n"
    with atomic_path(output) as tmp:
        Path(tmp).write_text(text)
    if publish:
        from crfmap.repro.publish import publish as publish_paper

        publish_paper(output)
    return output
