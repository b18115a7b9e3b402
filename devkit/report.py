"""Benchmark output: CSV files and Markdown tables (for the README)."""

import csv


def cell(value, digits=6):
    """A value as text: '' for None, floats with ``digits`` significant digits."""
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return str(value)


def write_csv(path, rows, fields):
    """Write ``rows`` (dicts; keys outside ``fields`` are left out) to the CSV file ``path``
    with a header of ``fields``; values through ``cell``."""
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(fields), extrasaction="ignore")
        writer.writeheader()
        for row in rows:
            writer.writerow({k: cell(v) for k, v in row.items()})


def markdown_table(header, rows, align=None):
    """A Markdown table: ``header`` (column titles), ``rows`` (sequences of cells, already
    text or anything ``str`` gives), ``align`` one letter per column, 'l' or 'r' (default: the
    first column left, the others right)."""
    align = align or "l" + "r" * (len(header) - 1)
    rule = {"l": "---", "r": "---:", "c": ":---:"}
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join(rule[a] for a in align) + "|"]
    lines += ["| " + " | ".join("" if c is None else str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)
