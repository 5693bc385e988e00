#!/usr/bin/python3
"""The tables of bench/scaling.sh from its JSON lines (scaling_table.py scaling.jsonl): per grid and stage
the median seconds at each thread count, the speed-up against one thread, and the serial share s of
Amdahl's law T(p) = T(1) (s + (1 - s) / p), least squares over the thread counts
(s = sum(x y) / sum(x x) with x = 1 - 1/p, y = T(p)/T(1) - 1/p); then peak RSS per output tet."""
import json
import statistics
import sys

STAGES = ["import", "tetrahedralize", "reorder", "orient", "connect", "write", "total"]


def serial_share(times):
    """times: {threads: seconds}, with 1 among the keys."""
    t1 = times[1]
    xs = [(1 - 1 / p, times[p] / t1 - 1 / p) for p in times if p > 1]
    den = sum(x * x for x, _ in xs)
    return sum(x * y for x, y in xs) / den if den > 0 and t1 > 0 else float("nan")


def main():
    rows = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
    for grid in sorted({r["grid"] for r in rows}):
        runs = [r for r in rows if r["grid"] == grid]
        threads = sorted({r["threads"] for r in runs})
        by = {t: [r for r in runs if r["threads"] == t] for t in threads}
        first = runs[0]
        print("### grid %d: %d tets, %d cores, median of %d, load %.1f-%.1f at the runs' starts\n" % (
            grid, first["tets"], first["cores"], len(by[threads[0]]), min(r["load"] for r in runs),
            max(r["load"] for r in runs)))
        print("| stage | " + " | ".join("%d thr s" % t for t in threads) + " | " +
              " | ".join("x%d" % t for t in threads[1:]) + " | serial share |")
        print("|---|" + "---|" * (2 * len(threads)))
        for stage in STAGES:
            med = {t: statistics.median(r["seconds"][stage] for r in by[t]) for t in threads}
            speed = ["%.2f" % (med[1] / med[t]) if 1 in med and med[t] > 0 else "-" for t in threads[1:]]
            share = serial_share(med) if 1 in med and len(threads) > 1 else float("nan")
            name = "**%s**" % stage if stage == "total" else stage
            print("| %s | %s | %s | %s |" % (name, " | ".join("%.3f" % med[t] for t in threads), " | ".join(speed),
                                           "-" if share != share else "%.0f%%" % (100 * share)))
        print("| peak RSS B/tet | %s |%s |" % (" | ".join(
            "%.1f" % statistics.median(r["peak_rss_bytes"] / r["tets"] for r in by[t]) for t in threads),
            " |" * len(threads)))
        print()


if __name__ == "__main__":
    main()
