#!/usr/bin/python3
"""Fit a cost model to bench/mpi_scaling.sh's JSON lines and predict a 1-billion-tet conversion.

usage: bench/mpi_scaling.sh > lines.json; bench/mpi_model.py lines.json [--cores-here 2]

Model, per rank, for N tets on P ranks (n = N / P each), from the runs with no more ranks than cores:
  local time  = n / rate                   rate: tets per CPU second per rank over read + tets + write
                                           (CPU seconds: this machine is shared and loaded, its wall
                                           times count waiting for a core)
  exchange    = x * n / bandwidth          x: bytes sent per tet (global ids + cut faces), measured;
                                           bandwidth: the network's per-rank share (an assumption: here
                                           the exchange is shared memory, so its measured time is not it)
  sync        = log2(P) * latency          collectives per phase (7 agreements, 4 all-to-alls, 1 gather)
  memory      = base + m * n               m: bytes per tet above the MPI/process base, fitted
  input/output = (i + f) * N bytes, read and written at the file system's bandwidth (an assumption)
"""
import json
import math
import sys


def load(path):
    single, runs, meta = None, {}, {}
    for line in open(path):
        line = line.strip()
        if not line.startswith("{"):
            continue
        r = json.loads(line)
        if "input_bytes" in r:
            meta = r
        elif r.get("single"):
            single = r
        else:
            runs[r["ranks"]] = r
    return single, runs, meta


def main():
    single, runs, meta = load(sys.argv[1])
    cores = int(sys.argv[sys.argv.index("--cores-here") + 1]) if "--cores-here" in sys.argv else 2
    fit = [r for p, r in sorted(runs.items()) if p <= cores]
    rates, mems, xs, bases, files = [], [], [], [], []
    for r in fit:
        c = r["cpu_seconds"]
        n = max(r["tets_per_rank"])
        rates.append(n / (c["read"] + c["tets"] + c["write"]))
        xs.append(sum(r["exchanged_bytes"]) / r["tets"])
        files.append(sum(r["file_bytes"]) / r["tets"])
    # memory: peak = base + m * n over every rank of every fitted run (least squares on two parameters)
    pts = [(n, b) for r in fit for n, b in zip(r["tets_per_rank"], r["peak_rss_bytes"])]
    mean_n = sum(n for n, _ in pts) / len(pts)
    mean_b = sum(b for _, b in pts) / len(pts)
    var = sum((n - mean_n) ** 2 for n, _ in pts)
    m = sum((n - mean_n) * (b - mean_b) for n, b in pts) / var if var > 0 else mean_b / mean_n
    base = mean_b - m * mean_n
    rate = sum(rates) / len(rates)
    x = sum(xs) / len(xs)
    f = sum(files) / len(files)
    i = meta.get("input_bytes", 0) / fit[0]["tets"]
    print("measured here (%d tets):" % fit[0]["tets"])
    for p, r in sorted(runs.items()):
        s, c = r["seconds"], r["cpu_seconds"]
        print("  %d rank(s)%s: wall %.2f s (read %.2f, ids %.2f, tets %.2f, cut %.2f, write %.2f); slowest rank's "
              "CPU s: read %.2f, ids %.2f, tets %.2f, cut %.2f, write %.2f; peak RSS per rank %s MiB; exchanged %s "
              "kB per rank" % (
                  p, " (oversubscribed)" if p > cores else "", s["total"], s["read"], s["ids"], s["tets"],
                  s["cut"], s["write"], c["read"], c["ids"], c["tets"], c["cut"], c["write"],
                  ", ".join("%.0f" % (b / 2**20) for b in r["peak_rss_bytes"]),
                  ", ".join("%.0f" % (b / 1e3) for b in r["exchanged_bytes"])))
    if single:
        print("  single process (tetpack convert --threads 1): %.2f s wall, %.2f CPU s, peak RSS %.0f MiB" %
              (single["seconds"], single["cpu_seconds"], single["peak_rss_bytes"] / 2**20))
    print("fitted: rate %.3g tets per CPU second per rank; memory %.0f MiB + %.0f bytes/tet; exchange %.1f bytes/tet; "
          "output %.1f bytes/tet; input %.1f bytes/tet (%s)" % (rate, base / 2**20, m, x, f, i, meta.get("input")))
    N = 1e9
    bandwidth, latency, fs = 1e9, 5e-6, 20e9  # per-rank network share B/s, per hop s, file system B/s
    print("prediction for N = 1e9 tets (assumptions: %.0f GB/s network per rank, %.0f us latency, "
          "%.0f GB/s parallel file system shared by all ranks for input and output, ranks with one core each and the same per-core speed as here):"
          % (bandwidth / 1e9, latency * 1e6, fs / 1e9))
    for p in (64, 256, 1024, 4096):
        n = N / p
        t = n / rate + x * n / bandwidth + 12 * math.log2(p) * latency + (f + i) * N / fs
        print("  P = %5d: %7.0f tets per rank, %6.1f s, %6.2f GiB per rank, %.1f GB exchanged in all, "
              "%.0f GB read, %.0f GB written" % (p, n, t, (base + m * n) / 2**30, x * N / 1e9, i * N / 1e9, f * N / 1e9))


main()
