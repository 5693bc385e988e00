#!/usr/bin/python3
"""Fit a cost model to bench/mpi_scaling.sh's JSON lines and predict a 1-billion-tet conversion.

usage: bench/mpi_scaling.sh > lines.json; bench/mpi_model.py lines.json [--cores-here 2]

Model, per rank, for N tets on P ranks (n = N / P each), from the runs with no more ranks than cores:
  local time  = n / rate                   rate: tets per second per rank over read + tets + write
  exchange    = x * n / bandwidth          x: bytes sent per tet (global ids + cut faces), measured;
                                           bandwidth: the network's per-rank share (an assumption: here
                                           the exchange is shared memory, so its measured time is not it)
  sync        = log2(P) * latency          collectives per phase (7 agreements, 4 all-to-alls, 1 gather)
  memory      = base + m * n               m: bytes per tet above the MPI/process base, fitted
  output      = f * N bytes, written in parallel at the file system's bandwidth (an assumption)
"""
import json
import math
import sys


def load(path):
    single, runs = None, {}
    for line in open(path):
        line = line.strip()
        if not line.startswith("{"):
            continue
        r = json.loads(line)
        if r.get("single"):
            single = r
        else:
            runs[r["ranks"]] = r
    return single, runs


def main():
    single, runs = load(sys.argv[1])
    cores = int(sys.argv[sys.argv.index("--cores-here") + 1]) if "--cores-here" in sys.argv else 2
    fit = [r for p, r in sorted(runs.items()) if p <= cores]
    rates, mems, xs, bases, files = [], [], [], [], []
    for r in fit:
        s = r["seconds"]
        n = max(r["tets_per_rank"])
        rates.append(n / (s["read"] + s["tets"] + s["write"]))
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
    print("measured here (%d tets):" % fit[0]["tets"])
    for p, r in sorted(runs.items()):
        s = r["seconds"]
        print("  %d rank(s)%s: total %.2f s (read %.2f, ids %.2f, tets %.2f, cut %.2f, write %.2f); peak RSS per "
              "rank %s MiB; exchanged %s kB per rank" % (
                  p, " (oversubscribed)" if p > cores else "", s["total"], s["read"], s["ids"], s["tets"],
                  s["cut"], s["write"], ", ".join("%.0f" % (b / 2**20) for b in r["peak_rss_bytes"]),
                  ", ".join("%.0f" % (b / 1e3) for b in r["exchanged_bytes"])))
    if single:
        print("  single process (tetpack convert --threads 1): %.2f s, peak RSS %.0f MiB" %
              (single["seconds"], single["peak_rss_bytes"] / 2**20))
    print("fitted: rate %.3g tets/s per rank; memory %.0f MiB + %.0f bytes/tet; exchange %.1f bytes/tet; "
          "output %.1f bytes/tet" % (rate, base / 2**20, m, x, f))
    N = 1e9
    bandwidth, latency, fs = 1e9, 5e-6, 20e9  # per-rank network share B/s, per hop s, file system B/s
    print("prediction for N = 1e9 tets (assumptions: %.0f GB/s network per rank, %.0f us latency, "
          "%.0f GB/s parallel file system, ranks with one core each and the same per-core speed as here):"
          % (bandwidth / 1e9, latency * 1e6, fs / 1e9))
    for p in (64, 256, 1024, 4096):
        n = N / p
        t = n / rate + x * n / bandwidth + 12 * math.log2(p) * latency + f * N / fs
        print("  P = %5d: %7.0f tets per rank, %6.1f s, %6.2f GiB per rank, %.1f GB exchanged in all, "
              "%.0f GB written" % (p, n, t, (base + m * n) / 2**30, x * N / 1e9, f * N / 1e9))


main()
