"""A planted effect: physics the user's nominal model leaves out, labelled with
the contract's effect ID. `draw` picks its sizes per seed from a stated range
(sizes a real SHD/CSD-17-class joint shows); `apply` puts it into the truth
(parameters or an added form) and, where needed, into what the user types."""
from __future__ import annotations


class Effect:
    id = "effect"
    expected_kind = ("added",)  # what a diagnosis that names it right reports
    parameters: tuple[str, ...] = ()  # the contract parameters that model it

    def draw(self, rng) -> dict:
        return {}

    def apply(self, truth: dict, user: dict, forms: list, sizes: dict) -> None:
        raise NotImplementedError

    def describe(self, sizes: dict) -> dict:
        return {"id": self.id, "expected_kind": list(self.expected_kind), "sizes": dict(sizes)}
