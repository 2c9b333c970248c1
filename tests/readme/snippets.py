#!/usr/bin/env python3
"""The README's code blocks, extracted and run as a reader would paste them.

    snippets.py list README.md                     the blocks: language, line, checked or skipped
    snippets.py run-sh README.md --build B --source S
        runs every ```sh block with bash (-e -o pipefail) in a new folder of its own (mkdtemp under $TMPDIR) in
        which build/, config/ and scripts/ are symlinks to B, S/config and S/scripts, as if in the repository root
    snippets.py extract README.md LANG INDEX       prints one block (for the C++ consumer build)

A block preceded by the line `<!-- snippet: skip -->` is not run (the quick-start commands, which CI runs itself).
The Python blocks are run by tests/python/test_readme.py from a folder outside the repository.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

FENCE = re.compile(r"^```(\w+)\s*$")
SKIP = "<!-- snippet: skip -->"


def blocks(path):
    """[(language, first line number, code, skipped)] of the fenced blocks of a Markdown file."""
    out, lines = [], open(path, encoding="utf-8").read().splitlines()
    i = 0
    while i < len(lines):
        m = FENCE.match(lines[i])
        if m:
            start, body = i + 1, []
            i += 1
            while i < len(lines) and lines[i].strip() != "```":
                body.append(lines[i])
                i += 1
            prev = next((lines[k].strip() for k in range(start - 2, -1, -1) if lines[k].strip()), "")
            out.append((m.group(1), start + 1, "\n".join(body) + "\n", prev == SKIP))
        i += 1
    return out


def run_sh(readme, build, source):
    failures = 0
    checked = [(line, code) for lang, line, code, skip in blocks(readme) if lang in ("sh", "bash") and not skip]
    if not checked:
        print(f"{readme}: no shell snippet to check", file=sys.stderr)
        return 1
    for line, code in checked:
        work = tempfile.mkdtemp(prefix="jointsim_readme_sh.")
        os.symlink(os.path.abspath(build), os.path.join(work, "build"))
        for d in ("config", "scripts"):
            os.symlink(os.path.join(os.path.abspath(source), d), os.path.join(work, d))
        p = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", code], cwd=work, capture_output=True, text=True,
                           timeout=600)
        if p.returncode != 0:
            failures += 1
            print(f"{readme}:{line}: the shell snippet failed with exit status {p.returncode} (kept in {work}):\n"
                  f"{code}--- stdout\n{p.stdout}--- stderr\n{p.stderr}", file=sys.stderr)
        else:
            print(f"{readme}:{line}: ok ({code.count(chr(10))} lines)")
            shutil.rmtree(work)
    return 1 if failures else 0


def main(argv):
    if len(argv) >= 2 and argv[0] == "list":
        for lang, line, code, skip in blocks(argv[1]):
            print(f"{lang}\t{line}\t{'skipped' if skip else 'checked'}")
        return 0
    if len(argv) == 6 and argv[0] == "run-sh" and argv[2] == "--build" and argv[4] == "--source":
        return run_sh(argv[1], argv[3], argv[5])
    if len(argv) == 4 and argv[0] == "extract":
        found = [code for lang, _, code, _ in blocks(argv[1]) if lang == argv[2]]
        k = int(argv[3])
        if k >= len(found):
            print(f"{argv[1]}: no {argv[2]} block number {k} (it has {len(found)})", file=sys.stderr)
            return 1
        sys.stdout.write(found[k])
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
