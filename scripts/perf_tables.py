"""Markdown tables from `hmblur bench --json` files (docs/performance.md is made of them).

    python scripts/perf_tables.py docs/perf/*.json
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

SHOWN_PASSES = {
    "hybrid": ("gbuffer", "motion_tiles", "select_tiles", "mask_displacement", "mask_edge_near",
               "ray_mask", "reveal", "reveal_shade", "hybrid_tilemax_x", "hybrid_composite"),
}


def load(paths):
    reports = [(Path(p).stem, json.loads(Path(p).read_text())) for p in paths]
    for _, r in reports:
        if r.get("animate_fps"):      # `hmblur bench --animate`: frames advance in time
            r["scene"] = f"{r['scene']} (animated, {r['animate_fps']:g} fps)"
    return reports


def frame_table(reports) -> str:
    lines = ["| scene | size | off | McGuire | UE4-style | hybrid | hybrid / McGuire | UE4 / McGuire |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for _, r in reports:
        m = r["modes"]

        def ms(mode):
            return f"{m[mode]['frame_ms']:.1f}" if mode in m else "-"
        ratios = r.get("ratios", {})

        def ratio(key):
            return f"{ratios[key]:.2f}" if key in ratios else "-"
        lines.append(f"| {r['scene']} | {r['size'][0]}x{r['size'][1]} | {ms('off')} | "
                     f"{ms('mcguire')} | {ms('ue4')} | {ms('hybrid')} | "
                     f"{ratio('hybrid/mcguire')} | {ratio('ue4/mcguire')} |")
    return "\n".join(lines)


def pass_table(reports) -> str:
    names = SHOWN_PASSES["hybrid"]
    lines = ["| scene | size | McGuire gather | " + " | ".join(names) + " |",
             "|---|---|---:|" + "---:|" * len(names)]
    for _, r in reports:
        h = r["modes"].get("hybrid", {}).get("passes", {})
        g = r["modes"].get("mcguire", {}).get("passes", {}).get("mcguire_gather")
        cells = [f"{h[n]:.1f}" if n in h else "-" for n in names]
        lines.append(f"| {r['scene']} | {r['size'][0]}x{r['size'][1]} | "
                     f"{g:.1f} | " + " | ".join(cells) + " |" if g else "")
    return "\n".join(x for x in lines if x)


def host_table(reports) -> str:
    """Frame time against the main thread's CPU time in it (host work), McGuire and
    hybrid, and the hybrid's host CPU by pass (the largest, ms)."""
    lines = ["| scene | size | McGuire frame / host CPU | hybrid frame / host CPU | "
             "frame difference | host CPU difference | hybrid host CPU by pass |",
             "|---|---|---:|---:|---:|---:|---|"]
    for _, r in reports:
        m, h = r["modes"].get("mcguire", {}), r["modes"].get("hybrid", {})
        if "frame_cpu_ms" not in m or "frame_cpu_ms" not in h:
            continue
        top = sorted(h.get("passes_cpu", {}).items(), key=lambda kv: -kv[1])[:5]
        lines.append(
            f"| {r['scene']} | {r['size'][0]}x{r['size'][1]} | "
            f"{m['frame_ms']:.1f} / {m['frame_cpu_ms']:.1f} | "
            f"{h['frame_ms']:.1f} / {h['frame_cpu_ms']:.1f} | "
            f"{h['frame_ms'] - m['frame_ms']:+.1f} | {h['frame_cpu_ms'] - m['frame_cpu_ms']:+.1f} | "
            + ", ".join(f"{n} {v:.2f}" for n, v in top) + " |")
    return "\n".join(lines)


def reveal_table(reports) -> str:
    lines = ["| scene | size | masked pixels | rays | reveal ms | of which tracing | "
             "M rays/s (whole / tracing) | bare Embree M rays/s | whole / bare | tracing / bare | "
             "read-back ms | whole / bare with bare tracing and the read-back | "
             "bare, stopping at the own object |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for _, r in reports:
        rv = r.get("reveal")
        if not rv:
            continue
        lines.append(
            f"| {r['scene']} | {r['size'][0]}x{r['size'][1]} | {rv['masked_pixels']} | "
            f"{rv['rays']} | {rv['reveal_ms']:.1f} | {rv['trace_ms']:.1f} | "
            f"{rv['rays_per_s'] / 1e6:.2f} / {rv['trace_rays_per_s'] / 1e6:.2f} | "
            f"{rv['embree_rays_per_s'] / 1e6:.2f} | {rv['fraction_of_embree'] or 0:.0%} | "
            f"{rv['trace_fraction_of_embree'] or 0:.0%} | "
            + (f"{rv['readback_ms']:.2f} | {rv['fraction_with_bare_tracing']:.0%} | "
               if rv.get("fraction_with_bare_tracing") else "- | - | ")
            + (f"{rv['embree_front_rays_per_s'] / 1e6:.2f} ({rv['fraction_of_embree_front']:.0%}) |"
               if rv.get("fraction_of_embree_front") else "- |"))
    return "\n".join(lines)


def scaling_table(reports) -> str:
    lines = ["| scene | size | speed x | masked pixels | rays | reveal ms | ms per 1000 rays |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for _, r in reports:
        for row in r.get("scaling", []):
            per = 1e3 * row["reveal_ms"] / row["rays"] if row["rays"] else 0.0
            lines.append(f"| {r['scene']} | {r['size'][0]}x{r['size'][1]} | {row['speed']:g} | "
                         f"{row['masked_pixels']} | {row['rays']} | {row['reveal_ms']:.2f} | "
                         f"{per:.2f} |")
    return "\n".join(lines)


def main(paths) -> int:
    reports = load(paths)
    print("### Frame time (median ms) and ratios\n")
    print(frame_table(reports))
    print("\n### Hybrid passes (median ms)\n")
    print(pass_table(reports))
    print("\n### Host CPU (the main thread's) in a frame, ms\n")
    print(host_table(reports))
    print("\n### Reveal throughput\n")
    print(reveal_table(reports))
    print("\n### Reveal cost against the mask\n")
    print(scaling_table(reports))
    print(f"\nDevice: {reports[0][1]['device']}" if reports else "")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
