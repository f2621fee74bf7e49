"""The performance tables, generated from `hmblur bench --json` files (docs/perf/*.json,
written by scripts/bench_all.sh).

    python scripts/perf_tables.py            # rewrite the marked tables in place
    python scripts/perf_tables.py --check    # exit 1 if a marked table is out of date
    python scripts/perf_tables.py --print docs/perf/*.json   # every table, to stdout

A table lives in a Markdown file between a pair of markers, e.g.

    <!-- perf:frames -->
    ...generated, do not edit...
    <!-- /perf:frames -->

and is replaced there as a whole. The blocks: `frames`, `passes`, `host`, `reveal`,
`scaling`, `device` (docs/performance.md uses them) and `readme` (README.md's table; a
file without blocks is left alone, but docs/performance.md must have some). A block name
without a table is an error, so a typo cannot leave a stale table behind.
"""
from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PERF = ROOT / "docs" / "perf"
DOCS = ROOT / "docs" / "performance.md"
README = ROOT / "README.md"

# The hybrid passes shown, in frame order; a column whose every median is below
# HIDE_BELOW_MS, or that no report has, is left out (a pass the configuration measured
# does not run, e.g. the range check's with hybrid.range_check off).
SHOWN_PASSES = ("gbuffer", "motion_tiles", "select_tiles", "mask_displacement",
                "mask_edge_near", "ray_mask", "reveal", "reveal_shade", "hybrid_tilemax_x",
                "hybrid_composite")
HIDE_BELOW_MS = 0.05
HOST_TOP = 3                # the hybrid's largest host-CPU passes listed per row

# The README's rows: (file stem, label); one row per size found, the animated ratio beside.
README_ROWS = [("living_room", "living_room"), ("thin", "thin"), ("basic", "basic (conformance)"),
               ("spinner", "spinner"), ("wheel", "wheel (keyed)"), ("rover", "rover (glTF: parents, skin)"),
               ("vase_pan", "vase_pan (conformance, camera moves)"),
               ("pan", "pan (camera moves)"), ("crowd", "crowd (32 movers, bench scene)"),
               ("crowd_pan", "crowd_pan (32 movers, camera moves)")]
README_SIZES = ("640x360",)     # (1280x720: docs/performance.md)

BLOCK = re.compile(r"(<!-- perf:([a-z_]+) -->\n)(.*?)(<!-- /perf:\2 -->)", re.S)


def load(paths) -> list[tuple[str, dict]]:
    reports = [(Path(p).stem, json.loads(Path(p).read_text())) for p in sorted(paths)]
    for _, r in reports:
        if r.get("animate_fps"):      # `hmblur bench --animate`: frames advance in time
            r["scene"] = f"{r['scene']} (animated, {r['animate_fps']:g} fps)"
    return reports


def size(r) -> str:
    return f"{r['size'][0]}x{r['size'][1]}"


def frame_table(reports) -> str:
    """Frame times, the ratios to McGuire, and the main thread's CPU time in a McGuire
    and a hybrid frame (host work: on llvmpipe it adds to the frame)."""
    lines = ["| scene | size | off | McGuire | UE4-style | Guertin | hybrid | hybrid / McGuire | "
             "UE4 / McGuire | Guertin / McGuire | host CPU McGuire / hybrid |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for _, r in reports:
        m, ratios = r["modes"], r.get("ratios", {})

        def ms(mode, key="frame_ms"):
            return f"{m[mode][key]:.1f}" if key in m.get(mode, {}) else "-"

        def ratio(key):
            return f"{ratios[key]:.2f}" if key in ratios else "-"
        lines.append(f"| {r['scene']} | {size(r)} | {ms('off')} | {ms('mcguire')} | "
                     f"{ms('ue4')} | {ms('guertin')} | {ms('hybrid')} | {ratio('hybrid/mcguire')} | "
                     f"{ratio('ue4/mcguire')} | {ratio('guertin/mcguire')} | {ms('mcguire', 'frame_cpu_ms')} / "
                     f"{ms('hybrid', 'frame_cpu_ms')} |")
    return "\n".join(lines)


def pass_table(reports) -> str:
    """The hybrid's passes beside McGuire's gather, one frame time over and over (the
    animated runs are in the frame and reveal tables)."""
    rows = [(r, r["modes"].get("hybrid", {}).get("passes", {}),
             r["modes"].get("mcguire", {}).get("passes", {}).get("mcguire_gather"))
            for _, r in reports if not r.get("animate_fps")]
    rows = [row for row in rows if row[1] and row[2] is not None]
    names = [n for n in SHOWN_PASSES if any(h.get(n, 0.0) >= HIDE_BELOW_MS for _, h, _ in rows)]
    lines = ["| scene | size | McGuire gather | " + " | ".join(names) + " |",
             "|---|---|---:|" + "---:|" * len(names)]
    for r, h, g in rows:
        cells = [f"{h[n]:.1f}" if n in h else "-" for n in names]
        lines.append(f"| {r['scene']} | {size(r)} | {g:.1f} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def host_table(reports) -> str:
    """Frame time against the main thread's CPU time in it (host work), McGuire and
    hybrid, and the hybrid's largest host-CPU passes (ms)."""
    lines = ["| scene | size | McGuire frame / host CPU | hybrid frame / host CPU | "
             "frame difference | host CPU difference | hybrid host CPU, largest passes |",
             "|---|---|---:|---:|---:|---:|---|"]
    for _, r in reports:
        m, h = r["modes"].get("mcguire", {}), r["modes"].get("hybrid", {})
        if "frame_cpu_ms" not in m or "frame_cpu_ms" not in h:
            continue
        top = sorted(h.get("passes_cpu", {}).items(), key=lambda kv: -kv[1])[:HOST_TOP]
        lines.append(
            f"| {r['scene']} | {size(r)} | "
            f"{m['frame_ms']:.1f} / {m['frame_cpu_ms']:.1f} | "
            f"{h['frame_ms']:.1f} / {h['frame_cpu_ms']:.1f} | "
            f"{h['frame_ms'] - m['frame_ms']:+.1f} | {h['frame_cpu_ms'] - m['frame_cpu_ms']:+.1f} | "
            + ", ".join(f"{n} {v:.2f}" for n, v in top) + " |")
    return "\n".join(lines)


def _pct(x) -> str:
    return f"{x:.0%}" if x else "-"


def reveal_table(reports) -> str:
    lines = ["| scene | size | rays | reveal ms | of which tracing | "
             "M rays/s (whole / tracing) | bare Embree M rays/s | whole / bare | "
             "tracing / bare | read-back ms | bound: bare tracing + read-back |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for _, r in reports:
        rv = r.get("reveal")
        if not rv or size(r) != "640x360":      # (1280x720: the same pattern, in the JSON)
            continue
        readback = (f"{rv['readback_ms']:.2f}" if rv.get("fraction_with_bare_tracing")
                    else "-")
        lines.append(
            f"| {r['scene']} | {size(r)} | {rv['rays']} | {rv['reveal_ms']:.1f} | "
            f"{rv['trace_ms']:.1f} | "
            f"{rv['rays_per_s'] / 1e6:.2f} / {rv['trace_rays_per_s'] / 1e6:.2f} | "
            f"{rv['embree_rays_per_s'] / 1e6:.2f} | {_pct(rv['fraction_of_embree'])} | "
            f"{_pct(rv['trace_fraction_of_embree'])} | {readback} | "
            f"{_pct(rv.get('fraction_with_bare_tracing'))} |")
    return "\n".join(lines)


def scaling_table(reports) -> str:
    lines = ["| scene | size | speed x | masked pixels | rays | reveal ms | ms per 1000 rays |",
             "|---|---|---:|---:|---:|---:|---:|"]
    for _, r in reports:
        for row in r.get("scaling", []):
            per = 1e3 * row["reveal_ms"] / row["rays"] if row["rays"] else 0.0
            lines.append(f"| {r['scene']} | {size(r)} | {row['speed']:g} | "
                         f"{row['masked_pixels']} | {row['rays']} | {row['reveal_ms']:.2f} | "
                         f"{per:.2f} |")
    return "\n".join(lines)


def device_line(reports) -> str:
    devices = sorted({r["device"] for _, r in reports})
    timing = sorted({r.get("pass_timing", "?") for _, r in reports})
    return (f"Device: {'; '.join(devices)}. Passes timed by {', '.join(timing)}."
            if reports else "No bench JSON found.")


def readme_table(reports) -> str:
    """The README's table: McGuire, UE4-style and hybrid frame times and the ratio per
    scene and size, the animated ratio beside the rows that have one."""
    by_stem = dict(reports)
    lines = ["| scene | size | McGuire ms | UE4-style ms | Guertin ms | hybrid ms | hybrid / McGuire "
             "| animated, 60 fps |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, label in README_ROWS:
        for sz in README_SIZES:
            r = by_stem.get(f"{name}_{sz}")
            if r is None:
                continue
            modes = r["modes"]

            def ms(m):
                return f"{modes[m]['frame_ms']:.1f}" if m in modes else "-"
            anim = by_stem.get(f"{name}_{sz}_animated")
            a = f"{anim['ratios']['hybrid/mcguire']:.2f}" if anim else "-"
            lines.append(f"| {label} | {sz} | {ms('mcguire')} | {ms('ue4')} | {ms('guertin')} | {ms('hybrid')} "
                         f"| {r['ratios']['hybrid/mcguire']:.2f} | {a} |")
    return "\n".join(lines)


TABLES = {"frames": frame_table, "passes": pass_table, "host": host_table,
          "reveal": reveal_table, "scaling": scaling_table, "device": device_line,
          "readme": readme_table}


def fill(text: str, reports, where: str) -> str:
    """`text` with every marked block replaced by its table."""
    def one(m):
        name = m.group(2)
        if name not in TABLES:
            print(f"perf_tables: {where}: unknown table block 'perf:{name}' "
                  f"(expected one of {', '.join(TABLES)})", file=sys.stderr)
            raise SystemExit(2)
        return m.group(1) + TABLES[name](reports) + "\n" + m.group(4)
    return BLOCK.sub(one, text)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("json", nargs="*", help="bench JSON files (default docs/perf/*.json)")
    ap.add_argument("--check", action="store_true",
                    help="change nothing; exit 1 if a marked table differs from the JSON")
    ap.add_argument("--print", action="store_true", dest="print_",
                    help="print every table to stdout instead of writing the files")
    args = ap.parse_args(argv)
    paths = args.json or sorted(PERF.glob("*.json"))
    if not paths:
        print(f"perf_tables: no bench JSON in {PERF}", file=sys.stderr)
        return 2
    reports = load(paths)
    if args.print_:
        for name, table in TABLES.items():
            print(f"<!-- perf:{name} -->\n{table(reports)}\n")
        return 0
    stale = []
    for path in (DOCS, README):
        if not path.exists():
            continue
        text = path.read_text()
        if path == DOCS and not BLOCK.search(text):
            print(f"perf_tables: {path}: no marked tables", file=sys.stderr)
            return 2
        new = fill(text, reports, str(path))
        if new != text:
            stale.append(path)
            if not args.check:
                path.write_text(new)
    for path in stale:
        print(f"perf_tables: {path.relative_to(ROOT)} "
              f"{'out of date' if args.check else 'updated'}", file=sys.stderr)
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
