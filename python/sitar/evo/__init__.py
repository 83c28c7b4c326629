"""evo's Python API on SiTAR's Rust library: change ``evo`` to ``sitar.evo`` in a script's
imports and it gives the same numbers, faster.

Mirrored (``python/README.md`` lists every function and every known difference):
``sitar.evo.core.trajectory``, ``.sync``, ``.metrics``, ``.geometry``, ``.units``,
``.result``, ``.lie_algebra`` (the pose helpers), and ``sitar.evo.tools.file_interface``
and ``.plot``. What is not mirrored raises ``NotImplementedError`` naming evo's function and
the nearest ``sitar`` equivalent.
"""


class EvoException(Exception):
    """The base of every sitar.evo error, as evo's (``message`` is the first argument)."""

    def __init__(self, *args, **kwargs):
        self.message = args[0] if len(args) >= 1 else ""
        super().__init__(*args, **kwargs)
