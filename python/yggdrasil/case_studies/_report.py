"""The results: ``case_studies.json``, ``case_studies.md`` and a log-scale SVG figure."""
from __future__ import annotations

import json
import math
from xml.sax.saxutils import escape


def _fmt(x):
    if x is None:
        return "–"
    if x >= 100:
        return f"{x:,.0f}"
    if x >= 10:
        return f"{x:.1f}"
    return f"{x:.2f}"


def write_json(path, doc):
    with open(path, "w") as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")


def label(row):
    scene = f" ({row['scene']})" if row.get("scene") else ""
    return f"{row['study']}{scene}: {row['operation']}"


def write_svg(path, rows):
    rows = [r for r in rows if r.get("ratio") and r.get("paper_ratio")]
    lo = min(min(r["ratio"], r["paper_ratio"]) for r in rows)
    hi = max(max(r["ratio"], r["paper_ratio"]) for r in rows)
    lo_e, hi_e = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
    left, width, bar, gap, top = 330, 460, 7, 6, 40
    height = top + len(rows) * (2 * bar + gap) + 40

    def x(v):
        return left + width * (math.log10(v) - lo_e) / (hi_e - lo_e)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{left + width + 30}" height="{height}" '
           f'font-family="sans-serif" font-size="11">',
           '<rect width="100%" height="100%" fill="white"/>',
           f'<text x="{left}" y="16" font-size="13">Speedup (original / Yggdrasil), log scale</text>',
           f'<rect x="{left}" y="22" width="10" height="8" fill="#9aa7b8"/><text x="{left + 14}" y="30">paper</text>',
           f'<rect x="{left + 60}" y="22" width="10" height="8" fill="#2b6cb0"/><text x="{left + 74}" y="30">this run</text>']
    bottom = height - 30
    for e in range(lo_e, hi_e + 1):
        xe = x(10 ** e)
        out.append(f'<line x1="{xe:.1f}" y1="{top - 4}" x2="{xe:.1f}" y2="{bottom}" stroke="#ddd"/>')
        out.append(f'<text x="{xe:.1f}" y="{bottom + 14}" text-anchor="middle">{10 ** e:g}×</text>')
    x1 = x(1)
    out.append(f'<line x1="{x1:.1f}" y1="{top - 4}" x2="{x1:.1f}" y2="{bottom}" stroke="#c53030"/>')
    for i, r in enumerate(rows):
        y = top + i * (2 * bar + gap)
        out.append(f'<text x="{left - 6}" y="{y + 2 * bar - 2}" text-anchor="end">{escape(label(r))}</text>')
        for k, (v, color) in enumerate(((r["paper_ratio"], "#9aa7b8"), (r["ratio"], "#2b6cb0"))):
            a, b = sorted((x1, x(v)))
            out.append(f'<rect x="{a:.1f}" y="{y + k * bar}" width="{max(b - a, 1):.1f}" height="{bar - 1}" fill="{color}">'
                       f'<title>{escape(label(r))}: {v:.3g}×</title></rect>')
    out.append("</svg>")
    with open(path, "w") as fh:
        fh.write("\n".join(out) + "\n")


def write_md(path, doc, svg_name):
    m = doc["machine"]
    lines = [
        "# The paper's case studies, reproduced from Python (issue 40)",
        "",
        f"Command: `{doc['command']}` ({doc['seconds']:.0f} s). Machine: {m['cpu']}, {m['cores']} cores, "
        f"load average {m['loadavg']} at the end, Python {m['python']}, spark_dsg {m['spark_dsg']}, "
        f"networkx {m['networkx']}, numpy {m['numpy']}, scipy {m['scipy']}. The machine is noisy and "
        "shared (another CI build may run on it during a run): per-call rows are medians over every timed call "
        "of every run; totals are per run, the median of the runs.",
        "",
        f"![speedups]({svg_name})",
        "",
        "| study | operation | original | Yggdrasil | ratio | paper (orig. / Ygg.) | paper ratio | target | met |",
        "|---|---|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in doc["rows"]:
        unit = r["unit"]
        paper = (f"{_fmt(r['paper_original'])} / {_fmt(r['paper_yggdrasil'])} {unit}"
                 if r.get("paper_original") is not None else "–")
        target = r.get("target")
        met = "–" if target is None else ("yes" if r["ratio"] >= target else "**no**")
        lines.append(f"| {label(r).split(':')[0]} | {r['operation']} | {_fmt(r['original'])} {unit} | "
                     f"{_fmt(r['yggdrasil'])} {unit} | {r['ratio']:.2f}× | {paper} | "
                     f"{_fmt(r['paper_ratio'])}{'' if r['paper_ratio'] is None else '×'} | {'–' if target is None else f'≥ {target:g}×'} | {met} |")
    lines.append("")
    for section in doc["notes"]:
        lines.append(section)
        lines.append("")
    with open(path, "w") as fh:
        fh.write("\n".join(lines))
