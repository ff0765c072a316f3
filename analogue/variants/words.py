"""What a variant says about itself on a page (issue 20: the report's prose composes these
instead of testing ``model.shot``, ``model.cubic``, ...).

A variant gives :class:`Phrase` objects for the parts of a page that list what a set of models
has (the circuit paragraph, the reduced equation, the family's theory references): the page
keeps one phrase per ``slot``, in slot order, and where models of one page word a slot
differently (Coulomb's ``Delta sgn(v)``, Stribeck's ``Delta(v) sgn(v)``) the wording that
``covers`` the most.  :func:`merge` does that; :func:`num` is the page's number format.
"""
from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any, NamedTuple

__all__ = ["EQUATION", "CIRCUIT", "REFERENCE", "ELEMENT_TERMS", "Phrase", "merge",
           "model_phrases", "num", "gamma_words"]

#: The slots of the lists: terms of the reduced equation, elements of the circuit paragraph,
#: references of the family's comparisons, the circuit-element terms of the family's budget.
EQUATION, CIRCUIT, REFERENCE, ELEMENT_TERMS = (range(0, 10), range(10, 20), range(20, 30),
                                               range(30, 40))


def num(x: float) -> str:
    """A page's number: 4 significant digits."""
    return f"{x:.4g}"


class Phrase(NamedTuple):
    """One part of a page's list: its place (``slot``), its words, and how much of the other
    wordings of its slot it covers (the larger wins)."""

    slot: int
    text: str
    covers: int = 0


def merge(phrases: Iterable[Phrase], slots: range) -> list[str]:
    """The texts of ``phrases`` in ``slots``, one per slot (the one that covers most), in slot
    order."""
    best: dict[int, Phrase] = {}
    for p in phrases:
        if p.slot not in slots:
            continue
        if p.slot not in best or p.covers > best[p.slot].covers:
            best[p.slot] = p
    return [best[s].text for s in sorted(best)]


def model_phrases(models: Iterable[Any]) -> list[Phrase]:
    """What the models' variants say of themselves, all together (for :func:`merge`)."""
    return [p for m in models
            for p in (*m.friction.page_phrases(), *m.noise_kind.page_phrases(),
                      *m.restoring.page_phrases(m.noise_kind))]


def gamma_words(gamma: float) -> str:
    """The white Gaussian part of a noise, in the model sentence."""
    if math.isfinite(gamma):
        return (f"gamma = {num(gamma)} (Gaussian velocity noise of intensity "
                f"1/gamma = {num(1 / gamma)})")
    return "gamma = inf (no Gaussian noise)"
