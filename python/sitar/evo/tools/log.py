"""evo.tools.log's ``configure_logging``: sitar.evo's messages (logger ``sitar.evo``) on
the console, as evo configures its ``evo`` logger."""

import logging
import sys
import typing

DEFAULT_LONG_FMT = "[%(levelname)s][%(asctime)s][%(module)s.%(funcName)s():%(lineno)s]\n%(message)s"


def configure_logging(verbose: bool = False, silent: bool = False, debug: bool = False,
                      console_fmt: typing.Optional[str] = None, file_fmt: str = DEFAULT_LONG_FMT,
                      local_logfile=None) -> None:
    """Messages of ``sitar.evo`` to stdout: warnings by default, info with ``verbose``,
    everything with ``debug``, nothing with ``silent``; also to ``local_logfile``."""
    logger = logging.getLogger("sitar.evo")
    logger.propagate = False
    for handler in list(logger.handlers):
        logger.removeHandler(handler)
    if silent:
        logger.addHandler(logging.NullHandler())
        return
    console = logging.StreamHandler(sys.stdout)
    console.setFormatter(logging.Formatter(console_fmt or "%(message)s"))
    logger.addHandler(console)
    if local_logfile:
        to_file = logging.FileHandler(local_logfile)
        to_file.setFormatter(logging.Formatter(file_fmt))
        logger.addHandler(to_file)
    logger.setLevel(logging.DEBUG if debug else logging.INFO if verbose else logging.WARNING)
