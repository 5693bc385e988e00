#!/usr/bin/python3
"""Run `tetpack check --json` on every case make_broken.py wrote and compare with the expectations.
Usage: run_corpus.py TETPACK OUTDIR [CASE-NAME-PREFIX]"""
import json
import os
import subprocess
import sys


def main():
    tetpack, outdir = sys.argv[1], sys.argv[2]
    prefix = sys.argv[3] if len(sys.argv) > 3 else ""
    with open(os.path.join(outdir, "expected.json")) as f:
        cases = json.load(f)
    failures = 0
    ran = 0
    for case in cases:
        if not case["name"].startswith(prefix):
            continue
        ran += 1
        path = os.path.join(outdir, case["file"])
        proc = subprocess.run([tetpack, "check", path, "--json", "--no-progress"] + case["args"],
                              capture_output=True, text=True)
        problems = []
        if proc.returncode != case["exit"]:
            problems.append("exit %d, expected %d (stderr: %s)" % (proc.returncode, case["exit"],
                                                                   proc.stderr.strip()[:300]))
        found = {}
        if proc.returncode in (0, 1):
            try:
                report = json.loads(proc.stdout)
                found = {f["name"]: f["count"] for f in report["findings"]}
            except (ValueError, KeyError) as e:
                problems.append("bad JSON: %s" % e)
        for name, want in case["expect"].items():
            got = found.get(name, 0)
            if (want == ">0" and got <= 0) or (want != ">0" and got != want):
                problems.append("%s: count %d, expected %s" % (name, got, want))
        for name in case["absent"]:
            if found.get(name, 0):
                problems.append("%s reported (%d) but must not be (near miss)" % (name, found[name]))
        if problems:
            failures += 1
            print("FAIL %s (%s): %s" % (case["name"], case["module"], "; ".join(problems)))
            print("     findings: %s" % json.dumps(found))
    print("run_corpus.py: %d cases, %d failed" % (ran, failures))
    if ran == 0:
        sys.exit("run_corpus.py: no case matched '%s'" % prefix)
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
