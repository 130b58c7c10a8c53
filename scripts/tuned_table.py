#!/usr/bin/env python3
"""Prints the table of src/core/tuned.h as the markdown rows of docs/method.md's "Tuned numbers"
section (tests/core/test_tuned.cpp checks that the two agree). Usage: scripts/tuned_table.py"""
import pathlib
import re

source = (pathlib.Path(__file__).resolve().parent.parent / "src/core/tuned.h").read_text()
text = re.sub(r"\\\n", " ", source)
rows = re.findall(r'X\((k\w+),\s*(\w+),\s*([-+0-9.eE]+?)f?,\s*"([^"]*)",\s*"([^"]*)"\)', text)
print("| number | value | fitted on | why |")
print("|---|---|---|---|")
for name, _type, value, fitted_on, why in rows:
    why = why.replace("|", "\\|")
    print(f"| `{name}` | {value} | {fitted_on} | {why} |")
