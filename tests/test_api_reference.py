"""docs/reference/api.md gives every exported function's exact signature."""

import inspect
from pathlib import Path

import ftc_mc

PAGE = Path(__file__).resolve().parents[1] / "docs" / "reference" / "api.md"


def _signature(func) -> str:
    """``name(params)`` without annotations, as the page writes it."""
    sig = inspect.signature(func)
    bare = sig.replace(parameters=[p.replace(annotation=inspect.Parameter.empty)
                                   for p in sig.parameters.values()],
                       return_annotation=inspect.Signature.empty)
    return f"ftc_mc.{func.__name__}{bare}"


def test_api_reference_signatures():
    text = PAGE.read_text()
    for name in ftc_mc.__all__:
        assert f"### `{name}`" in text, f"docs/reference/api.md: no section for {name}"
        assert _signature(getattr(ftc_mc, name)) in text, (
            f"docs/reference/api.md: the signature of {name} is stale")
