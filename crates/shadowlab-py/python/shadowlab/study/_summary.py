"""A study's summary: per technique and parameter set, the median and worst error and time
across its scenes, lights and cameras, as a table (CSV, Markdown, text) and an SVG plot."""

import math
from pathlib import Path
from typing import Any, Dict, List
from xml.sax.saxutils import escape

#: The summary's columns.
SUMMARY_COLUMNS = [
    "label", "technique", "rows", "median_mean_abs_error", "worst_mean_abs_error",
    "median_mismatch_rate", "worst_mismatch_rate", "median_time_ms", "worst_time_ms",
]


def summarize(rows: Any) -> Any:
    """One line per run label (technique and parameter set), in first-seen order: over its
    rows (scenes × lights × cameras × frames), the median and the worst (largest) mean
    error, mismatch rate and time. Failed jobs' error rows are left out."""
    import pandas as pd

    ok = rows[rows["error"].isna() & rows["label"].notna()]
    out: List[Dict[str, Any]] = []
    for label in dict.fromkeys(ok["label"]):
        g = ok[ok["label"] == label]
        out.append({
            "label": label, "technique": g["technique"].iloc[0], "rows": len(g),
            "median_mean_abs_error": g["mean_abs_error"].median(),
            "worst_mean_abs_error": g["mean_abs_error"].max(),
            "median_mismatch_rate": g["mismatch_rate"].median(),
            "worst_mismatch_rate": g["mismatch_rate"].max(),
            "median_time_ms": g["time_ms"].median(), "worst_time_ms": g["time_ms"].max(),
        })
    return pd.DataFrame(out, columns=SUMMARY_COLUMNS)


def markdown(summary: Any, rows: Any = None) -> str:
    """The summary as a Markdown table, followed by the failed jobs' errors."""
    head = ["technique", "rows", "median error", "worst error", "median mismatch",
            "worst mismatch", "median ms", "worst ms"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in summary.itertuples():
        lines.append(
            f"| {r.label} | {r.rows} | {r.median_mean_abs_error:.5f} | {r.worst_mean_abs_error:.5f} "
            f"| {r.median_mismatch_rate * 100:.3f}% | {r.worst_mismatch_rate * 100:.3f}% "
            f"| {r.median_time_ms:.2f} | {r.worst_time_ms:.2f} |"
        )
    if rows is not None:
        failed = rows[rows["error"].notna()]
        if len(failed):
            lines.append(f"\n{len(failed)} job(s) failed:")
            lines += [f"- {r.scene} / {r.light} / {r.camera}: {r.error}" for r in failed.itertuples()]
    return "\n".join(lines) + "\n"


def svg(summary: Any) -> str:
    """Median error against median time, one point per run (log-log), with a bar up to the
    worst error; written without a plotting library."""
    w, h, left, right, top, bottom = 720, 480, 70, 190, 30, 50
    pts = [r for r in summary.itertuples()
           if r.median_time_ms > 0 and math.isfinite(r.median_time_ms)]
    eps = 1e-6
    xs = [math.log10(max(r.median_time_ms, 1e-3)) for r in pts] or [0.0]
    ys = [math.log10(max(v, eps)) for r in pts
          for v in (r.median_mean_abs_error, r.worst_mean_abs_error)] or [0.0]
    x0, x1 = math.floor(min(xs)), math.ceil(max(xs) + 1e-9)
    y0, y1 = math.floor(min(ys)), math.ceil(max(ys) + 1e-9)
    x1, y1 = max(x1, x0 + 1), max(y1, y0 + 1)
    sx = lambda v: left + (v - x0) / (x1 - x0) * (w - left - right)  # noqa: E731
    sy = lambda v: h - bottom - (v - y0) / (y1 - y0) * (h - top - bottom)  # noqa: E731
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" '
           f'font-family="sans-serif" font-size="11">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<text x="{w / 2}" y="18" text-anchor="middle" font-size="13">median error against '
           'median time (bars: up to the worst error; an error of 0 on the bottom line)</text>']
    for e in range(x0, x1 + 1):
        out.append(f'<line x1="{sx(e):.1f}" y1="{top}" x2="{sx(e):.1f}" y2="{h - bottom}" stroke="#ddd"/>'
                   f'<text x="{sx(e):.1f}" y="{h - bottom + 15}" text-anchor="middle">{10.0 ** e:g}</text>')
    for e in range(y0, y1 + 1):
        out.append(f'<line x1="{left}" y1="{sy(e):.1f}" x2="{w - right}" y2="{sy(e):.1f}" stroke="#ddd"/>'
                   f'<text x="{left - 5}" y="{sy(e) + 4:.1f}" text-anchor="end">{10.0 ** e:g}</text>')
    out.append(f'<text x="{(left + w - right) / 2}" y="{h - 12}" text-anchor="middle">time (ms)</text>')
    out.append(f'<text x="16" y="{(top + h - bottom) / 2}" text-anchor="middle" '
               f'transform="rotate(-90 16 {(top + h - bottom) / 2})">mean abs error</text>')
    palette = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2",
               "#7f7f7f", "#bcbd22", "#17becf"]
    for i, r in enumerate(pts):
        c = palette[i % len(palette)]
        x = sx(math.log10(max(r.median_time_ms, 1e-3)))
        ym = sy(math.log10(max(r.median_mean_abs_error, eps)))
        yw = sy(math.log10(max(r.worst_mean_abs_error, eps)))
        out.append(f'<line x1="{x:.1f}" y1="{ym:.1f}" x2="{x:.1f}" y2="{yw:.1f}" stroke="{c}"/>'
                   f'<circle cx="{x:.1f}" cy="{ym:.1f}" r="4" fill="{c}"/>'
                   f'<circle cx="{w - right + 14}" cy="{top + 14 * i + 10}" r="4" fill="{c}"/>'
                   f'<text x="{w - right + 22}" y="{top + 14 * i + 14}">{escape(str(r.label))}</text>')
    out.append("</svg>\n")
    return "\n".join(out)


def write_summary(rows: Any, out: "str | Path") -> Any:
    """Writes ``rows.parquet`` (every row), ``summary.csv``, ``summary.md`` and
    ``summary.svg`` into ``out``; returns the summary."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    summary = summarize(rows)
    rows.to_parquet(out / "rows.parquet", index=False)
    summary.to_csv(out / "summary.csv", index=False)
    (out / "summary.md").write_text(markdown(summary, rows))
    (out / "summary.svg").write_text(svg(summary))
    return summary
