"""The ``sitar`` command: the Rust CLI binary the wheel carries (``sitar/bin/sitar``, its
evo-compatible and beyond-evo commands), run in place of this process."""

import os
import sys
from pathlib import Path

BINARY = Path(__file__).resolve().parent / "bin" / "sitar"


def main() -> None:
    """Replaces this process by the bundled ``sitar`` binary with the same arguments."""
    if not BINARY.is_file():
        sys.stderr.write(
            f"sitar: error: this install has no sitar command ({BINARY} is missing): "
            "install the wheel (python/build-wheel makes it), or build the whole CLI with "
            "`cargo build --release -p sitar-cli`\n"
        )
        sys.exit(2)
    sys.stdout.flush()
    os.execv(str(BINARY), ["sitar", *sys.argv[1:]])


if __name__ == "__main__":
    main()
