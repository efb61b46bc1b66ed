"""Draw the package structure as an SVG: one box per package (its lines of code, and those of
each subpackage), one arrow per package that imports another (every import, functions
included), packages placed in the layers of the import-linter contract (``pyproject.toml``),
the registries marked.

    python bench/structure/draw_structure.py docs/architecture.svg

Reads the code only (:mod:`bench.structure.count_structure` finds the files and the imports);
nothing of the project is run.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import Counter
from pathlib import Path

# a sibling: run as python bench/structure/draw_structure.py
from count_structure import ROOT, source_files

#: Top (CLI) to ground, as the layers contract orders them; packages on one row share a layer.
ROWS = (("hapticrom",), ("hardware",), ("planner", "calibration"), ("studies",),
        ("surrogate",), ("fem",), ("motorlaw", "fieldspec", "figstyle"))
#: The extension points: package -> what is registered there, one per line.
REGISTRIES = {"surrogate": "registry: kinds.py (kinds)",
              "hardware": "registry: backends.py (devices)",
              "fieldspec": "errors.py: the two error bases"}
W, H, GAP_X, GAP_Y, MARGIN = 240, 86, 40, 40, 20
#: Characters of small text on one line of a box.
LINE_CHARS = 40


def package_graph(root: Path = ROOT) -> tuple[Counter[str], Counter[tuple[str, str]]]:
    """Lines per package and per subpackage (``"surrogate/sweep"``), and (importer, imported)
    package pairs with their import count."""
    lines: Counter[str] = Counter()
    edges: Counter[tuple[str, str]] = Counter()
    packages = {p for row in ROWS for p in row}
    for path in source_files(root):
        parts = path.relative_to(root).parts
        pkg = parts[0]
        text = path.read_text(encoding="utf-8")
        lines[pkg] += text.count("\n")
        if len(parts) > 2:
            lines[f"{pkg}/{parts[1]}"] += text.count("\n")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.Import):
                targets = [a.name.split(".")[0] for a in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
                targets = [node.module.split(".")[0]]
            else:
                continue
            edges.update((pkg, t) for t in targets if t in packages and t != pkg)
    return lines, edges


def _subpackage_lines(lines: Counter[str], pkg: str) -> list[str]:
    """The subpackages of ``pkg`` with their lines, largest first, wrapped into box lines."""
    subs = sorted(((n, k.split("/", 1)[1]) for k, n in lines.items()
                   if k.startswith(f"{pkg}/")), reverse=True)
    words = [f"{name}/ {n / 1000:.1f}k" for n, name in subs]
    rows: list[str] = []
    for word in words:
        if rows and len(rows[-1]) + 2 + len(word) <= LINE_CHARS:
            rows[-1] += f", {word}"
        else:
            rows.append(word)
    return rows


def svg(lines: Counter[str], edges: Counter[tuple[str, str]]) -> str:
    """The picture as SVG text."""
    width = MARGIN * 2 + 3 * W + 2 * GAP_X
    where: dict[str, tuple[float, float]] = {}
    for r, row in enumerate(ROWS):
        x0 = (width - (len(row) * W + (len(row) - 1) * GAP_X)) / 2
        for i, pkg in enumerate(row):
            where[pkg] = (x0 + i * (W + GAP_X), MARGIN + 30 + r * (H + GAP_Y))
    height = MARGIN * 2 + 30 + len(ROWS) * (H + GAP_Y) + 30
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}" font-family="DejaVu Sans, Arial, sans-serif">',
           '<defs><marker id="a" viewBox="0 0 10 10" refX="10" refY="5" markerWidth="7" '
           'markerHeight="7" orient="auto"><path d="M0,0 L10,5 L0,10 z" fill="#555"/>'
           '</marker></defs>', f'<rect width="{width}" height="{height}" fill="white"/>',
           f'<text x="{MARGIN}" y="{MARGIN + 8}" font-size="15" font-weight="bold">hapticrom: '
           'the packages and their imports</text>']
    # spread the ends along a box's edge, in the order of the other ends, so arrows stay apart
    outs = {p: sorted((q for (o, q) in edges if o == p), key=lambda q: where[q]) for p in where}
    ins = {p: sorted((o for (o, q) in edges if q == p), key=lambda o: where[o]) for p in where}

    def along(x: float, items: list[str], item: str) -> float:
        return x + W * (items.index(item) + 1) / (len(items) + 1)

    for (a, b), n in sorted(edges.items()):
        (xa, ya), (xb, yb) = where[a], where[b]
        x1, y1 = along(xa, outs[a], b), ya + H if yb > ya else ya
        x2, y2 = along(xb, ins[b], a), yb if yb > ya else yb + H
        if ya == yb:  # same layer: side to side
            x1, y1 = (xa + W, ya + H / 2) if xb > xa else (xa, ya + H / 2)
            x2, y2 = (xb, yb + H / 2) if xb > xa else (xb + W, yb + H / 2)
        colour = "#c0392b" if yb < ya else "#555"  # an arrow up would break the layers
        stroke = 1 + min(n, 40) / 10
        out.append(f'<line x1="{x1:.0f}" y1="{y1:.0f}" x2="{x2:.0f}" y2="{y2:.0f}" '
                   f'stroke="{colour}" stroke-opacity="0.55" stroke-width="{stroke:.1f}" '
                   'marker-end="url(#a)"/>')
    for pkg, (x, y) in where.items():
        reg = REGISTRIES.get(pkg)
        out.append(f'<rect x="{x:.0f}" y="{y:.0f}" width="{W}" height="{H}" rx="6" '
                   f'fill="{"#e8f1fb" if reg else "#f4f4f4"}" stroke="#333"/>')
        out.append(f'<text x="{x + 10:.0f}" y="{y + 22:.0f}" font-size="14" '
                   f'font-weight="bold">{pkg}/</text>')
        out.append(f'<text x="{x + W - 10:.0f}" y="{y + 22:.0f}" font-size="11" '
                   f'text-anchor="end" fill="#555">{lines[pkg]:,} lines</text>')
        text_y = y + 40
        if reg:
            out.append(f'<text x="{x + 10:.0f}" y="{text_y:.0f}" font-size="11" '
                       f'fill="#1a5276">{reg}</text>')
            text_y += 16
        for row in _subpackage_lines(lines, pkg):
            out.append(f'<text x="{x + 10:.0f}" y="{text_y:.0f}" font-size="10" '
                       f'fill="#555">{row}</text>')
            text_y += 14
    out.append(f'<text x="{MARGIN}" y="{height - 26}" font-size="11" fill="#555">An arrow '
               'points to what is imported (width: how many imports); blue boxes hold a '
               'registry.</text>')
    out.append(f'<text x="{MARGIN}" y="{height - 10}" font-size="11" fill="#555">Drawn from '
               'the code by `python bench/structure/draw_structure.py '
               'docs/architecture.svg`.</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Write the SVG to the path given."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="SVG file to write")
    args = parser.parse_args(argv)
    lines, edges = package_graph()
    args.out.write_text(svg(lines, edges), encoding="utf-8")
    packages = sum("/" not in k for k in lines)
    print(f"wrote {args.out}: {packages} packages, {len(edges)} package imports")
    return 0


if __name__ == "__main__":
    sys.exit(main())
