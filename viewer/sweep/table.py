"""The sweep's outputs, assembled from the cell files: the tidy table (CSV and Parquet), a
plot of each metric against each swept parameter, and summary.md.

One row per (scene, time, shutter, size, samples, seed, variant, region); a cell that
failed is one row with its `error` and no variant. Rows follow the sweep file's order
(scenes, times, shutters, sizes, samples, seeds, then variants and regions), so the same
cells give the same files byte for byte (frame_ms, with --timing, excepted).
"""
from __future__ import annotations

import csv
import io
import math
import statistics

import pyarrow as pa
import pyarrow.parquet as pq

from viewer.io.imageio import OutputSet
from viewer.eval.plot import PALETTE, line_plots
from viewer.eval.strip import REGION_ORDER
from .spec import Sweep

METRICS = ("flip", "psnr", "ssim")
LEADING = ("scene", "time", "shutter", "size", "width", "height", "samples", "seed",
           "variant", "mode")
TRAILING = ("region", "pixels", "flip", "psnr", "ssim")
AXIS_LABEL = {"time": "frame time (s)", "shutter": "shutter (s)", "size": "megapixels",
              "samples": "reference sub-frames", "seed": "seed"}
METRIC_LABEL = {"flip": "FLIP (lower is better)", "psnr": "PSNR dB (higher is better)",
                "ssim": "SSIM (higher is better)", "frame_ms": "frame ms (warm median)"}


def columns(spec: Sweep, timing: bool) -> list[str]:
    return (list(LEADING) + spec.set_keys() + list(TRAILING)
            + (["frame_ms"] if timing else []) + ["error", "cell"])


def rows_of(spec: Sweep, cells: list[dict], timing: bool) -> list[dict]:
    """The table's rows from cell results in the sweep's order."""
    by_name = {v.name: v for v in spec.variants}
    rows = []
    for c in cells:
        w, h = c["size"] if c["size"] else (None, None)
        head = {"scene": c["scene"], "time": c["time"], "shutter": c["shutter"],
                "size": f"{w}x{h}" if w else None, "width": w, "height": h,
                "samples": c["samples"], "seed": c["seed"], "error": c["error"], "cell": c["key"]}
        if c["error"] is not None:
            rows.append(head)
            continue
        for r in c["rows"]:
            v = by_name[r["variant"]]
            row = {**head, "variant": r["variant"], "mode": r["mode"], **v.sets,
                   "region": r["region"], "pixels": r["pixels"],
                   **{m: _number(r[m]) for m in METRICS}}
            if timing:
                row["frame_ms"] = r.get("frame_ms")
            rows.append(row)
    cols = columns(spec, timing)
    return [{k: row.get(k) for k in cols} for row in rows]


def _number(v):
    return float(v) if isinstance(v, str) else v      # "inf" (a JSON cell file's PSNR)


def _arrow_type(values):
    present = [v for v in values if v is not None]
    if present and all(isinstance(v, bool) for v in present):
        return pa.bool_()
    if present and all(isinstance(v, int) and not isinstance(v, bool) for v in present):
        return pa.int64()
    if present and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in present):
        return pa.float64()
    return pa.string()


def arrow_table(rows: list[dict], cols: list[str]) -> pa.Table:
    arrays = {}
    for k in cols:
        values = [r[k] for r in rows]
        kind = _arrow_type(values)
        if kind == pa.float64():
            values = [None if v is None else float(v) for v in values]
        elif kind == pa.string():
            values = [None if v is None else str(v) for v in values]
        arrays[k] = pa.array(values, type=kind)
    return pa.table(arrays) if rows else pa.table({k: pa.array([], pa.string()) for k in cols})


def csv_bytes(rows: list[dict], cols: list[str]) -> bytes:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow(["" if r[k] is None else (str(r[k]).lower() if isinstance(r[k], bool)
                                             else repr(r[k]) if isinstance(r[k], float)
                                             else r[k]) for k in cols])
    return buf.getvalue().encode("utf-8")


def parquet_bytes(table: pa.Table) -> bytes:
    sink = pa.BufferOutputStream()
    pq.write_table(table, sink)
    return sink.getvalue().to_pybytes()


# --- plots ---------------------------------------------------------------------------------

def _x(axis: str, row: dict):
    if axis == "size":
        return row["width"] * row["height"] / 1e6
    v = row[axis]
    return float(v) if isinstance(v, (int, float)) else None


def _mean(values):
    vals = [v for v in values if v is not None and math.isfinite(v)]
    return statistics.fmean(vals) if vals else None


def plot_axes(spec: Sweep) -> list[tuple[str, str, str]]:
    """(axis, series by, x label) of every plot the sweep may make."""
    return ([(a, "variant", AXIS_LABEL[a]) for a in spec.swept()]
            + [(k, "family", k) for k in spec.grid_keys()])


def plot_name(metric: str, axis: str) -> str:
    return f"{metric}_vs_{axis.replace('.', '_')}.png"


def plot_names(spec: Sweep, timing: bool) -> list[str]:
    """Every plot file the sweep may write (the ones its cells' values make are some)."""
    metrics = list(METRICS) + (["frame_ms"] if timing else [])
    return [plot_name(m, a) for a, _, _ in plot_axes(spec) for m in metrics]


def plots(spec: Sweep, rows: list[dict], timing: bool) -> dict[str, bytes]:
    """{file name: PNG}: each metric against each swept cell parameter (series: the
    variants) and against each variant grid key (series: the variant tables using it),
    a panel per region, each point the mean over everything else (scenes, other axes)."""
    from viewer.io.imageio import png_bytes
    ok = [r for r in rows if r["error"] is None]
    axes = [(a, by, label) for a, by, label in plot_axes(spec)
            if by == "variant" or len({str(r[a]) for r in ok if r.get(a) is not None}) > 1]
    family = {v.name: v.family for v in spec.variants}
    metrics = list(METRICS) + (["frame_ms"] if timing else [])
    out = {}
    for axis, by, x_label in axes:
        for metric in metrics:
            regions = ["all"] if metric == "frame_ms" else [g for g in REGION_ORDER
                                                            if any(r["region"] == g for r in ok)]
            panels, names = [], []
            for region in regions:
                groups: dict = {}
                for r in ok:
                    x = _x(axis, r)
                    if r["region"] != region or x is None:
                        continue
                    name = r["variant"] if by == "variant" else family[r["variant"]]
                    groups.setdefault(name, {}).setdefault(x, []).append(r[metric])
                series = {}
                for name, points in groups.items():
                    xs = sorted(points)
                    series[name] = (xs, [_mean(points[x]) for x in xs])
                    names.append(name)
                panels.append((f"{region} ({len({r['scene'] for r in ok})} scenes, mean)",
                               series))
            names = list(dict.fromkeys(names))
            if not names:
                continue
            colours = {n: PALETTE[i % len(PALETTE)] for i, n in enumerate(names)}
            img = line_plots(panels, colours, x_label, METRIC_LABEL[metric],
                             title=f"{metric} against {axis}")
            out[plot_name(metric, axis)] = png_bytes(img)
    return out


# --- summary -------------------------------------------------------------------------------

def _fmt(v, digits=4) -> str:
    if v is None:
        return "-"
    return f"{v:.{digits}f}" if math.isfinite(v) else ("inf" if v > 0 else "-inf")


def _own(v) -> str:
    return "the scene's" if v is None else f"{v:g}"


def summary(spec: Sweep, rows: list[dict], cells: list[dict], facts: dict,
            plot_names: list[str], timing: bool) -> str:
    ok = [r for r in rows if r["error"] is None]
    failed = [c for c in cells if c["error"] is not None]
    regions = [g for g in REGION_ORDER if any(r["region"] == g for r in ok)]
    lines = [f"# Sweep {spec.path.name}", "",
             f"{len(cells)} cells: {len(cells) - len(failed)} done, {len(failed)} failed; "
             f"{len(spec.scenes)} scenes x {len(spec.times)} times x {len(spec.shutters)} "
             f"shutters x {len(spec.sizes)} sizes x {len(spec.samples)} sample counts x "
             f"{len(spec.seeds)} seeds, {len(spec.variants)} variants each.", ""]
    lines += [f"- {k}: {v}" for k, v in facts.items()] + [""]
    lines += ["## Mean over the cells, per variant and region", "",
              "FLIP / PSNR dB / SSIM against each cell's reference"
              + (", and the warm frame time (median of the cells' medians)" if timing else "")
              + ".", "",
              "| variant | mode | " + " | ".join(regions) + (" | frame ms |" if timing else " |"),
              "| --- | --- | " + " | ".join("---:" for _ in regions) + (" | ---: |" if timing else " |")]
    for v in spec.variants:
        mine = [r for r in ok if r["variant"] == v.name]
        cellsv = []
        for g in regions:
            rr = [r for r in mine if r["region"] == g]
            cellsv.append(" / ".join((_fmt(_mean([r["flip"] for r in rr])),
                                      _fmt(_mean([r["psnr"] for r in rr]), 2),
                                      _fmt(_mean([r["ssim"] for r in rr])))))
        line = f"| {v.name} | {v.mode} | " + " | ".join(cellsv)
        if timing:
            ms = [r["frame_ms"] for r in mine if r["region"] == "all" and r["frame_ms"] is not None]
            line += f" | {_fmt(statistics.median(ms) if ms else None, 1)}"
        lines.append(line + " |")
    lines.append("")
    if failed:
        lines += ["## Failed cells", ""]
        lines += [f"- {c['scene']}, t = {_own(c['time'])}, shutter {_own(c['shutter'])}, "
                  f"{'x'.join(map(str, c['size'])) if c['size'] else _own(None)}: {c['error']}"
                  for c in failed]
        lines.append("")
    if plot_names:
        lines += ["## Plots", ""] + [f"- [{n}](plots/{n})" for n in plot_names] + [""]
    lines += ["## Files", "", "- table.csv, table.parquet: one row per scene, time, shutter, "
              "size, samples, seed, variant and region (a failed cell: one row with its error)",
              "- cells/KEY.json: each finished cell, keyed by what it depends on", ""]
    return "\n".join(lines)


def write_outputs(folder, spec: Sweep, cells: list[dict], facts: dict, timing: bool) -> list[dict]:
    """table.csv, table.parquet, plots/*.png and summary.md, all or none, into `folder`
    (an outdir.OutputFolder; an earlier run's plots that this one does not make go); the
    rows."""
    rows = rows_of(spec, cells, timing)
    cols = columns(spec, timing)
    out = folder.path
    files = OutputSet(folder)
    data_csv = csv_bytes(rows, cols)
    data_pq = parquet_bytes(arrow_table(rows, cols))
    files.add(out / "table.csv", lambda f: f.write(data_csv))
    files.add(out / "table.parquet", lambda f: f.write(data_pq))
    pngs = plots(spec, rows, timing)
    for name, data in pngs.items():
        files.add(out / "plots" / name, lambda f, d=data: f.write(d))
    text = summary(spec, rows, cells, facts, list(pngs), timing).encode("utf-8")
    files.add(out / "summary.md", lambda f: f.write(text))
    for name in folder.owned_files():
        if name.startswith("plots/") and name.removeprefix("plots/") not in pngs:
            files.remove(out / name)
    files.commit()
    return rows
