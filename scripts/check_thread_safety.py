#!/usr/bin/env python3
"""Clang's thread-safety analysis over pdsm's own sources (STYLE.md: lock annotations the
compiler checks). Every translation unit of the build that takes a lock (it includes
absl/synchronization/mutex.h, directly or through one of our headers) is compiled by clang with
-fsyntax-only -Wthread-safety -Werror; any violation fails. No object is written: it reuses the
build's compile commands (BUILD/compile_commands.json) with clang in place of the compiler.

Usage: check_thread_safety.py BUILD_DIR [--jobs N]
Exit: 0 clean, 1 a violation (clang's messages on stderr), 2 no clang++ or no compile commands.
"""
import concurrent.futures
import json
import os
import re
import shlex
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FOLDERS = ("core/", "rpc/", "server/", "worker/", "client/", "gl/")
INCLUDE = re.compile(r'^#include "([^"]+)"', re.M)


def takes_a_lock(path, seen):
    """True when `path` or a project header it includes includes absl's mutex."""
    if path in seen:
        return False
    seen.add(path)
    try:
        text = open(path, encoding="utf-8").read()
    except OSError:
        return False
    for header in INCLUDE.findall(text):
        if header == "absl/synchronization/mutex.h":
            return True
        local = os.path.join(ROOT, header)
        if os.path.exists(local) and takes_a_lock(local, seen):
            return True
    return False


def clang_command(entry, clang):
    args = entry.get("arguments") or shlex.split(entry["command"])
    out = [clang]
    skip = False
    for a in args[1:]:
        if skip:
            skip = False
            continue
        if a in ("-o", "-MF", "-MT", "-MQ"):
            skip = True
            continue
        if a in ("-c", "-MD", "-MMD") or a.startswith("-fdiagnostics-color"):
            continue
        out.append(a)
    return out + ["-fsyntax-only", "-Wthread-safety", "-Wthread-safety-beta",
                  "-Werror=thread-safety", "-Wno-unknown-warning-option"]


def main():
    if len(sys.argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    build = sys.argv[1]
    jobs = int(sys.argv[sys.argv.index("--jobs") + 1]) if "--jobs" in sys.argv else os.cpu_count()
    clang = shutil.which("clang++") or shutil.which("clang++-14")
    commands = os.path.join(build, "compile_commands.json")
    if not clang or not os.path.exists(commands):
        print("check_thread_safety: needs clang++ and %s" % commands, file=sys.stderr)
        return 2
    entries = []
    for e in json.load(open(commands)):
        rel = os.path.relpath(e["file"], ROOT)
        if rel.startswith(FOLDERS) and takes_a_lock(e["file"], set()):
            entries.append(e)

    def check(e):
        r = subprocess.run(clang_command(e, clang), cwd=e["directory"], capture_output=True,
                           text=True)
        return e["file"], r.returncode, r.stderr

    failed = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for path, rc, err in pool.map(check, entries):
            if rc != 0:
                failed += 1
                sys.stderr.write(err)
    print("check_thread_safety: %d translation units, %d with violations"
          % (len(entries), failed))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
