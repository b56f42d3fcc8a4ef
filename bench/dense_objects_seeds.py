"""Dense alone on the blocks of ``bench_dsm_objects``, over several seeds (issue 19).

``bench_dsm_objects`` runs every matcher on one held-out seed (about 6 minutes); to compare
dense options this script builds the ``small`` / ``aerial`` blocks of the given seeds once
(into a folder that is kept, so later runs reuse them) and matches only dense, with optional
:class:`~photodem.algorithms.matching.dense.DenseOptions` fields as JSON. The figures are
those of the bench (``bench_dsm_objects._judge``): object interior and open cells within
0.5 m, terrain RMS in ‰ of the flying height (and the terrain NMAD in m), outline IoU, wall
error (GSD), and the time of ``match_model_dense``.

Usage (from the repository root)::

    .venv/bin/python -m bench.dense_objects_seeds BLOCKS_DIR aerial:1 aerial:2 small:11 \\
        [--options '{"refine": 8}'] [--json OUT.jsonl]

Not part of ``make bench``; the numbers go to ``docs/decisions.md`` (issue 19, part V).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List

#: the model of each block size (as ``bench_dsm_objects.BLOCKS``)
MODELS = {"small": "0102_0103", "aerial": "0101_0102"}


def block(root: Path, size: str, seed: int) -> Dict[str, Any]:
    """The block of ``size`` and ``seed`` under ``root``, built once as the bench builds it
    (``bench_dsm_objects._block``)."""
    from .bench_dsm_objects import _block

    folder = root / f"{size}{seed}"
    info_file = folder / "bench_block.json"
    if info_file.exists():
        return json.loads(info_file.read_text())
    info = _block(folder, size, seed)
    info_file.write_text(json.dumps(info))
    return info


def dense_row(info: Dict[str, Any], options: Dict[str, Any]) -> Dict[str, Any]:
    """The bench's figures of one dense DSM of the block ``info``."""
    from photodem.algorithms.matching.dense_model import match_model_dense

    from .bench_dsm_accuracy import _terrain_errors
    from .bench_dsm_objects import _judge

    model = MODELS[info["size"]]
    with tempfile.TemporaryDirectory(prefix="dense-objects-") as tmp:
        t0 = time.perf_counter()
        r = match_model_dense(info["project"], model, tmp, **info["heights"], **options)
        seconds = time.perf_counter() - t0
        j = _judge(info, model, r["dsm"])
        nmad = _terrain_errors(r["dsm"], info["truth"])["nmad_m"]
    return {"block": info["size"], "seed": info["seed"], "options": options,
            "interior_0_5_pct": j["interior_0_5_pct"], "open_0_5_pct": j["open_0_5_pct"],
            "terrain_permille_h": j["terrain_permille_h"], "terrain_nmad_m": nmad,
            "iou": j["iou"],
            "wall_gsd": j["wall_gsd"], "seconds": seconds}


def main(argv: List[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("blocks", help="folder of the built blocks (kept between runs)")
    ap.add_argument("specs", nargs="+", help="SIZE:SEED, e.g. aerial:1 small:11")
    ap.add_argument("--options", default="{}", help="dense options as JSON")
    ap.add_argument("--json", help="append the rows to this JSON-lines file")
    args = ap.parse_args(argv)
    options = json.loads(args.options)
    root = Path(args.blocks)
    root.mkdir(parents=True, exist_ok=True)
    for spec in args.specs:
        size, seed = spec.split(":")
        row = dense_row(block(root, size, int(seed)), options)
        print(json.dumps(row), flush=True)
        if args.json:
            with open(args.json, "a") as out:
                out.write(json.dumps(row) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
