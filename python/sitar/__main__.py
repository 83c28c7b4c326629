"""The ``sitar`` command: the Rust CLI itself, run in this process through the extension."""

import sys

from sitar import _sitar


def main() -> None:
    """Runs ``sitar`` on this process's arguments and exits with its status."""
    sys.stdout.flush()
    sys.exit(_sitar.main(["sitar", *sys.argv[1:]]))


if __name__ == "__main__":
    main()
