"""Write the golden result files of ``tests/test_golden.py`` (``tests/golden/``).

Run only when behaviour changes on purpose, in a commit of its own whose message
and issue note say what moved and why::

    .venv/bin/python scripts/maintenance/make_golden.py
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))

import ftc_mc  # noqa: E402,F401  -- first: it pins OpenBLAS's kernels before numpy loads (blas.py)
from golden_cases import GOLDEN, all_frames  # noqa: E402


def main() -> None:
    GOLDEN.mkdir(exist_ok=True)
    for path, df in all_frames():
        tmp = path.with_suffix(".tmp")
        df.to_parquet(tmp, index=False)
        tmp.replace(path)
        print(f"wrote {path.relative_to(GOLDEN.parent.parent)}: {len(df)} rows, "
              f"{len(df.columns)} columns")


if __name__ == "__main__":
    main()
