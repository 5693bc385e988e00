#!/usr/bin/env python3
"""The Markdown table of bench/gpu/run.sh's JSON lines (standard library only).
usage: table.py results.jsonl > results.md"""
import json
import sys


def main(path):
    rows = [json.loads(line) for line in open(path) if line.strip().startswith("{")]
    if not rows:
        print("no results")
        return 1
    print(f"GPU benchmark on **{rows[0]['device']}**, {rows[0]['size']}x{rows[0]['size']}, "
          f"median of {rows[0]['frames']} frames; setup = device + upload + pipeline + first frame.\n")
    print("| mesh | layout | tets | effects | setup s (device / upload / pipeline) | first frame ms "
          "| frame ms wall | frame ms GPU | tet steps/s | secondary rays | device B/tet | PSNR dB | CPU ref ms |")
    print("|---|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        s = r["setup"]
        gpu = f"{1e3 * r['frame_gpu_s']:.2f}" if r["frame_gpu_s"] >= 0 else "–"
        psnr = f"{r['psnr_db']:.1f}" if r["psnr_db"] >= 0 else "–"
        cpu = f"{1e3 * r['cpu_frame_s']:.0f}" if r["cpu_frame_s"] >= 0 else "–"
        print(f"| {r['mesh']} | {r['layout']} | {r['tets']:,} | {r['effect']} | {r['setup_s']:.3f} "
              f"({s['device']:.3f} / {s['upload']:.3f} / {s['pipeline']:.3f}) | {1e3 * r['first_frame_s']:.1f} "
              f"| {1e3 * r['frame_wall_s']:.2f} | {gpu} | {r['tet_steps_per_s']:.3g} | {r['secondary_rays']:,} "
              f"| {r['device_bytes_per_tet']:.1f} | {psnr} | {cpu} |")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
