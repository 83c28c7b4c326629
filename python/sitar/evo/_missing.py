"""``NotImplementedError`` for the parts of evo's API that ``sitar.evo`` does not mirror,
naming evo's function and the nearest ``sitar`` equivalent."""

from typing import Callable, Dict


def missing(module: str, table: Dict[str, str]) -> Callable[[str], object]:
    """A module ``__getattr__`` (PEP 562): names in ``table`` (evo's names, each with the
    nearest sitar equivalent) raise NotImplementedError; other names AttributeError."""

    def __getattr__(name: str) -> object:
        if name in table:
            raise NotImplementedError(
                f"{module}.{name} (evo) is not mirrored by sitar.{module}; "
                f"nearest sitar equivalent: {table[name]}"
            )
        raise AttributeError(f"module 'sitar.{module}' has no attribute '{name}'")

    return __getattr__
