#!/usr/bin/python3
"""Every --option the documentation names for a range_nlm_* tool exists in that tool's --help.

Checks README.md and docs/*.md of SOURCE_DIR against the tools in TOOLS_DIR:
- every command written out (in a code block or an inline code span) that starts with a tool's
  name: the --options up to the end of the command (a pipe, ';', '&&', '#' or the span's end);
  lines ending in a backslash continue the command;
- in docs/usage.md, every --option in the first column of a table row of the section
  '## range_nlm_NAME' (that tool's option reference).
Prints each option that is missing, with file and line, and exits 1 if there is one.

  check_doc_options.py SOURCE_DIR TOOLS_DIR
"""
import pathlib
import re
import subprocess
import sys

TOOLS = ("range_nlm_denoise", "range_nlm_bench", "range_nlm_synth", "range_nlm_eval", "range_nlm_render")
OPTION = re.compile(r"(?<![\w-])--([a-z][a-z0-9]*(?:-[a-z0-9]+)*)")
COMMAND = re.compile(r"(?:^|[\s`(/])(" + "|".join(TOOLS) + r")\b([^`|;#&\n]*)")


def help_options(tools_dir, tool):
    path = pathlib.Path(tools_dir) / tool
    if not path.is_file():
        sys.exit(f"check_doc_options.py: {path} does not exist (build the tools first)")
    run = subprocess.run([str(path), "--help"], capture_output=True, text=True, timeout=60)
    if run.returncode != 0:
        sys.exit(f"check_doc_options.py: '{path} --help' exited with {run.returncode}: {run.stderr.strip()}")
    options = set(re.findall(r"^\s+(?:-\w \[ )?--([a-z][a-z0-9-]*)", run.stdout, re.M))
    if not options:
        sys.exit(f"check_doc_options.py: '{path} --help' lists no options")
    return options


def logical_lines(text):
    """(first line number, text) with backslash-continued lines joined, and in prose the lines an
    inline code span runs across (an odd number of backticks so far)."""
    out, pending, start, fenced = [], "", 0, False
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
        if not pending:
            start = number
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        if not fenced and (pending + line).count("`") % 2 == 1:
            pending += line + " "
            continue
        out.append((start, pending + line))
        pending = ""
    if pending:
        out.append((start, pending))
    return out


def commands(text):
    """(line, tool, option) of every command written out in the text."""
    found = []
    for number, line in logical_lines(text):
        for match in COMMAND.finditer(line):
            for option in OPTION.findall(match.group(2)):
                found.append((number, match.group(1), option))
    return found


def reference_tables(text):
    """(line, tool, option) of the first column of the tables under '## range_nlm_NAME'."""
    found, tool = [], None
    for number, line in enumerate(text.splitlines(), 1):
        heading = re.match(r"^## (\S+)", line)
        if heading:
            tool = heading.group(1) if heading.group(1) in TOOLS else None
            continue
        if tool and line.startswith("|"):
            first = line.split("|")[1]
            for option in OPTION.findall(first):
                found.append((number, tool, option))
    return found


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    source, tools_dir = pathlib.Path(sys.argv[1]), sys.argv[2]
    known = {tool: help_options(tools_dir, tool) for tool in TOOLS}
    files = [source / "README.md"] + sorted((source / "docs").glob("*.md"))
    missing, checked = [], 0
    for path in files:
        text = path.read_text(encoding="utf-8")
        found = commands(text)
        if path.name == "usage.md":
            found += reference_tables(text)
        for number, tool, option in found:
            checked += 1
            if option not in known[tool]:
                missing.append(f"{path.relative_to(source)}:{number}: {tool} has no option --{option}")
    for line in sorted(set(missing)):
        print(line)
    if checked == 0:
        sys.exit("check_doc_options.py: found no tool options in the documentation")
    print(f"{checked} option mentions checked in {len(files)} files, {len(set(missing))} missing")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
