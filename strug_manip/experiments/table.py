"""Table I: mean discounted return ± standard error per (solver, domain).

Layout as in the paper: solvers are rows, domains columns; cells within
``BOLD_MARGIN`` = 2 points of the column's best mean are bold. The oracle's row (STRUG
knowing the cabinet, :data:`BOUNDS`) is an upper bound shown beside the solvers: it is
never bold and never the column's best.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

BOLD_MARGIN = 2.0

#: Display names of the paper's rows and columns.
SOLVER_TITLES = {
    "random": "Random",
    "pomcp": "POMCP (Disc)",
    "pomcpow": "POMCPOW",
    "entropy": "Entropy Regularized",
    "active": "Active Learning",
    "strug": "STRUG",
    "oracle": "Oracle (STRUG, true model)",
}
#: Rows that bound the solvers rather than compete with them (not bold, not the best).
BOUNDS: tuple[str, ...] = ("oracle",)
DOMAIN_TITLES = {
    "tiger": "Tiger",
    "tigerclassic": "TigerClassic",
    "extendedtiger": "ExtendedTiger",
    "lightdark1d": "LightDark 1D",
    "lightdark2d": "LightDark 2D",
    "shelf": "Shelf",
    "opendrawer": "Open Drawer",
    "opendoor": "Open Door",
}

#: The paper's Table I, (mean, stderr) per solver and domain, for side-by-side reading.
PAPER_TABLE_I: dict[str, dict[str, tuple[float, float]]] = {
    "random": {"tiger": (-1.62, 0.98), "extendedtiger": (-0.21, 0.89),
               "lightdark1d": (-5.43, 0.65), "lightdark2d": (-3.13, 0.14),
               "shelf": (-9.34, 0.20), "opendrawer": (-9.47, 0.05), "opendoor": (-9.54, 0.04)},
    "pomcp": {"tiger": (5.67, 0.75), "extendedtiger": (-0.02, 0.98),
              "lightdark1d": (1.30, 0.98), "lightdark2d": (-0.57, 0.12),
              "shelf": (9.02, 0.00), "opendrawer": (-1.00, 0.33), "opendoor": (-1.50, 0.41)},
    "pomcpow": {"tiger": (6.49, 0.66), "extendedtiger": (-0.37, 0.81),
                "lightdark1d": (2.60, 0.97), "lightdark2d": (-1.20, 0.89),
                "shelf": (8.62, 0.19), "opendrawer": (1.30, 0.71), "opendoor": (0.20, 0.71)},
    "entropy": {"tiger": (6.25, 0.31), "extendedtiger": (3.95, 0.34),
                "lightdark1d": (0.12, 0.94), "lightdark2d": (1.26, 0.41),
                "shelf": (3.91, 0.11), "opendrawer": (0.34, 1.18), "opendoor": (-0.15, 0.97)},
    "active": {"tiger": (5.59, 0.28), "extendedtiger": (3.96, 0.33),
               "lightdark1d": (5.50, 0.82), "lightdark2d": (2.13, 1.29),
               "shelf": (1.62, 0.92), "opendrawer": (1.49, 1.91), "opendoor": (1.03, 0.84)},
    "strug": {"tiger": (6.34, 0.31), "extendedtiger": (2.31, 0.25),
              "lightdark1d": (5.80, 0.62), "lightdark2d": (3.55, 0.91),
              "shelf": (9.02, 0.00), "opendrawer": (4.22, 1.60), "opendoor": (5.21, 1.39)},
}  # fmt: skip


def mean_stderr(values: Sequence[float]) -> tuple[float, float]:
    """Mean and standard error (sample std with ddof=1 over sqrt(n); 0 for n < 2)."""
    n = len(values)
    if n == 0:
        return math.nan, math.nan
    mean = sum(values) / n
    if n < 2:
        return mean, 0.0
    var = sum((v - mean) ** 2 for v in values) / (n - 1)
    return mean, math.sqrt(var / n)


def summarize(records: Iterable[dict[str, Any]]) -> dict[str, dict[str, dict[str, float]]]:
    """``{domain: {solver: {"mean", "stderr", "n"}}}`` from result records."""
    groups: dict[tuple[str, str], list[float]] = {}
    for r in records:
        groups.setdefault((r["domain"], r["solver"]), []).append(float(r["return"]))
    out: dict[str, dict[str, dict[str, float]]] = {}
    for (dom, sol), vals in groups.items():
        mean, se = mean_stderr(vals)
        out.setdefault(dom, {})[sol] = {"mean": mean, "stderr": se, "n": len(vals)}
    return out


def _ordered(names: Iterable[str], canonical: Iterable[str]) -> list[str]:
    names = set(names)
    known = [n for n in canonical if n in names]
    return known + sorted(names - set(known))


def _bold_cells(summary: dict[str, dict[str, dict[str, float]]]) -> set[tuple[str, str]]:
    bold = set()
    for dom, cells in summary.items():
        rivals = {s: c for s, c in cells.items() if s not in BOUNDS}
        if not rivals:
            continue
        best = max(c["mean"] for c in rivals.values())
        bold |= {(dom, s) for s, c in rivals.items() if c["mean"] >= best - BOLD_MARGIN}
    return bold


def layout(summary: dict[str, dict[str, dict[str, float]]]) -> tuple[list[str], list[str]]:
    """(domains, solvers) in the paper's order."""
    domains = _ordered(summary, DOMAIN_TITLES)
    solvers = _ordered({s for d in summary.values() for s in d}, SOLVER_TITLES)
    return domains, solvers


def to_markdown(summary: dict[str, dict[str, dict[str, float]]], *, with_paper: bool = True) -> str:
    """Markdown Table I (bold within 2 points of the column best), then the paper's values."""
    domains, solvers = layout(summary)
    bold = _bold_cells(summary)
    head = "| | " + " | ".join(DOMAIN_TITLES.get(d, d) for d in domains) + " |"
    lines = [head, "|---" * (len(domains) + 1) + "|"]
    for s in solvers:
        cells = []
        for d in domains:
            c = summary[d].get(s)
            if c is None:
                cells.append("–")
                continue
            text = f"{c['mean']:.2f} ± {c['stderr']:.2f}"
            cells.append(f"**{text}**" if (d, s) in bold else text)
        lines.append(f"| {SOLVER_TITLES.get(s, s)} | " + " | ".join(cells) + " |")
    n = sorted({int(c["n"]) for d in summary.values() for c in d.values()})
    lines.append("")
    lines.append(
        f"Mean discounted return ± standard error over {'/'.join(map(str, n))} seeds; "
        f"bold: within {BOLD_MARGIN:g} points of the column's best."
    )
    if with_paper:
        lines += ["", "Paper (Table I), same cells:", "", head, lines[1]]
        for s in solvers:
            row = [
                "{:.2f} ± {:.2f}".format(*PAPER_TABLE_I[s][d])
                if d in PAPER_TABLE_I.get(s, {})
                else "–"
                for d in domains
            ]
            lines.append(f"| {SOLVER_TITLES.get(s, s)} | " + " | ".join(row) + " |")
    return "\n".join(lines) + "\n"


def write_csv(summary: dict[str, dict[str, dict[str, float]]], path: Path) -> None:
    """One row per (domain, solver): mean, stderr, n, bold, paper mean and stderr."""
    domains, solvers = layout(summary)
    bold = _bold_cells(summary)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(
            ["domain", "solver", "mean", "stderr", "n", "bold", "paper_mean", "paper_stderr"]
        )
        for d in domains:
            for s in solvers:
                c = summary[d].get(s)
                if c is None:
                    continue
                paper = PAPER_TABLE_I.get(s, {}).get(d, (math.nan, math.nan))
                w.writerow(
                    [
                        d,
                        s,
                        f"{c['mean']:.4f}",
                        f"{c['stderr']:.4f}",
                        int(c["n"]),
                        int((d, s) in bold),
                        paper[0],
                        paper[1],
                    ]
                )


def write_png(summary: dict[str, dict[str, dict[str, float]]], path: Path) -> None:
    """Table I rendered as a figure (bold cells as in the paper)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    domains, solvers = layout(summary)
    bold = _bold_cells(summary)
    text = [
        [
            f"{summary[d][s]['mean']:.2f} ± {summary[d][s]['stderr']:.2f}"
            if s in summary[d]
            else "–"
            for d in domains
        ]
        for s in solvers
    ]
    fig, ax = plt.subplots(figsize=(1.9 * len(domains) + 2.0, 0.42 * len(solvers) + 0.9))
    ax.axis("off")
    tab = ax.table(
        cellText=text,
        rowLabels=[SOLVER_TITLES.get(s, s) for s in solvers],
        colLabels=[DOMAIN_TITLES.get(d, d) for d in domains],
        loc="center",
        cellLoc="center",
    )
    tab.auto_set_font_size(False)
    tab.set_fontsize(10)
    tab.scale(1.0, 1.4)
    for (r, c), cell in tab.get_celld().items():
        if r >= 1 and c >= 0 and (domains[c], solvers[r - 1]) in bold:
            cell.get_text().set_fontweight("bold")
            cell.set_facecolor("#e8f1fb")
    n = sorted({int(c["n"]) for d in summary.values() for c in d.values()})
    ax.set_title(f"Mean discounted return ± s.e. ({'/'.join(map(str, n))} seeds)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
