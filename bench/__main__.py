"""Run every benchmark (``bench/bench_*.py``) and report the results.

Each benchmark module has ``run() -> dict`` returning ``{"title": str, "rows": [dict, ...],
"notes": [str, ...]}``; a module whose peer or data is missing returns ``{"skipped": reason}``.
Results go to ``bench/results/<name>.json`` and a Markdown summary to ``bench/results/README.md``.

Usage: ``python -m bench [name ...]``
"""

from __future__ import annotations

import importlib
import json
import pkgutil
import sys
import time
import traceback
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _table(rows: list) -> str:
    if not rows:
        return "(no rows)\n"
    keys = list(rows[0])
    for row in rows[1:]:
        keys += [k for k in row if k not in keys]
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for row in rows:
        cells = []
        for k in keys:
            v = row.get(k, "")
            cells.append(f"{v:.4g}" if isinstance(v, float) else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list) -> int:
    wanted = set(argv)
    names = sorted(m.name for m in pkgutil.iter_modules([str(HERE)]) if m.name.startswith("bench_"))
    out_dir = HERE / "results"
    out_dir.mkdir(exist_ok=True)
    report = [f"# PhotoDEM benchmarks ({time.strftime('%Y-%m-%d %H:%M')})\n"]
    failed = 0
    for name in names:
        if wanted and name not in wanted and name[len("bench_"):] not in wanted:
            continue
        print(f"== {name}", flush=True)
        start = time.perf_counter()
        try:
            result = importlib.import_module(f"bench.{name}").run()
        except Exception:  # a broken benchmark must not hide the others
            traceback.print_exc()
            result = {"error": traceback.format_exc(limit=3)}
            failed += 1
        result["wall_s"] = round(time.perf_counter() - start, 2)
        (out_dir / f"{name}.json").write_text(json.dumps(result, indent=2, default=str))
        if "skipped" in result:
            text = f"skipped: {result['skipped']}\n"
        elif "error" in result:
            text = f"error:\n```\n{result['error']}\n```\n"
        else:
            text = _table(result.get("rows", []))
            text += "".join(f"\n- {n}" for n in result.get("notes", [])) + "\n"
        print(text, flush=True)
        report.append(f"## {result.get('title', name)}\n\n{text}")
    (out_dir / "README.md").write_text("\n".join(report))
    print(f"Results in {out_dir}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
