#!/usr/bin/env python3
"""The firmware guide's table (docs/guides/firmware.md), from the figures `firmware/sequence.sh` wrote to
docs/results/firmware/sequence*.txt (one row per target and set). Prints it; with --check, compares it
with the guide's table (between `<!-- firmware-table -->` and the next blank line) and exits 1
when they differ; with --write, replaces it."""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TARGETS = [
    ("Cortex-M4F", "docs/results/firmware/sequence.txt"),
    ("Cortex-M4F, `hw-sqrt`", "docs/results/firmware/sequence-hw-sqrt.txt"),
    ("Cortex-M0+ (soft float)", "docs/results/firmware/sequence-m0.txt"),
    ("RISC-V riscv32imac (soft float)", "docs/results/firmware/sequence-riscv.txt"),
    ("Cortex-M4F, a 0.3 m robot", "docs/results/firmware/sequence-body-0.3.txt"),
]
SUMMARY = re.compile(
    r"\): (\d+)/(\d+) goals reached, path ([\d.]+) m, (\d+) plan calls, \d+ expansions "
    r"\(([\d.]+) per call\)"
)
TIMES = re.compile(r"per-call time: median ([\d.]+) ms, worst ([\d.]+) ms")


def table():
    rows = [
        "| target | set | goals | calls | path | expansions per call | median call | worst call |",
        "|---|---|---|---:|---:|---:|---:|---:|",
    ]
    for name, doc in TARGETS:
        text = (ROOT / doc).read_text()
        for block in text.split("== ")[1:]:
            kind = block.split()[0]
            collisions = sum(int(c) for c in re.findall(r"(\d+) collisions", block))
            s = SUMMARY.search(block)
            t = TIMES.search(block)
            reached, goals, path, calls, per = s.groups()
            rows.append(
                f"| {name} | {kind} | {reached}/{goals}, {collisions} collisions | "
                f"{int(calls):,} | {float(path):,.1f} m | {per} | {t.group(1)} ms | {t.group(2)} ms |"
            )
    return "\n".join(rows) + "\n"


def main():
    want = table()
    readme = ROOT / "docs" / "guides" / "firmware.md"
    text = readme.read_text()
    marker = "<!-- firmware-table -->\n"
    start = text.index(marker) + len(marker)
    end = text.index("\n\n", start) + 1
    if "--check" in sys.argv:
        if text[start:end] != want:
            sys.stderr.write("docs/guides/firmware.md's firmware table differs from docs/results/firmware/sequence*.txt:\n")
            sys.stderr.write(want)
            sys.exit(1)
    elif "--write" in sys.argv:
        readme.write_text(text[:start] + want + text[end:])
    else:
        sys.stdout.write(want)


if __name__ == "__main__":
    main()
