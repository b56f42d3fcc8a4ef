"""Print the record of a test run the hang alarm ended (``tests/conftest.py``), shortly.

    python3 tools/hang_report.py TRACE_DIR

CI shows only the last lines of the output, so this runs after pytest and prints each
thread's own frames (pytest's and pluggy's left out) and, last, the test that hung. Prints
nothing when the run was not ended by the alarm (no stack dump).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import List

#: Frames of the test runner itself, left out: they are the same in every dump.
RUNNER = ("/_pytest/", "/pluggy/", "/pytest/__main__.py", "<frozen runpy>")
FRAMES_PER_THREAD = 8


def condensed(dump: str) -> List[str]:
    """Each thread's header and its first frames outside the test runner."""
    lines: List[str] = []
    kept = 0
    for line in dump.splitlines():
        if not line.startswith("  "):  # "Thread 0x… (most recent call first):" or "Timeout …"
            lines.append(line)
            kept = 0
        elif not any(part in line for part in RUNNER) and kept < FRAMES_PER_THREAD:
            lines.append(line)
            kept += 1
    return lines


def main(folder: str) -> int:
    trace = Path(folder)
    stacks = trace / "stacks"
    if not stacks.is_file() or stacks.stat().st_size == 0:
        return 0
    current = trace / "current"
    test = current.read_text().strip() if current.is_file() else "(unknown)"
    print("\n".join(["", "=== the hang alarm ended the run; threads (own frames) ==="]
                    + condensed(stacks.read_text(errors="replace"))
                    + [f"=== hung test: {test} ==="]), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
