"""The rule of the scripts whose ``--quick`` run writes a partial report: it needs an ``--out-dir`` of its own, so
that results/ keeps the full one. Light (the standard library only): checked before a script's slow imports."""

import sys


def refuse_quick_into_results(args, script: str) -> None:
    """With ``args.quick`` and no ``args.out_dir``: one line on stderr naming ``script``, exit 2."""
    if args.quick and args.out_dir is None:
        print(f"{script}: --quick writes a partial report: give --out-dir (results/ keeps the full one)",
              file=sys.stderr)
        sys.exit(2)
