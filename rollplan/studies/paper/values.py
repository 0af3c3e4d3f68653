"""The paper's printed numbers (Section III.C) and how a computed number is judged against one.

Svinin, Morinaga, Yamamoto, "On the Geometric Phase Approach to Motion Planning
for a Spherical Rolling Robot in Dynamic Formulation" (the paper this toolbox
implements; equation numbers throughout rollplan refer to it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PAPER", "K_RANGE", "A_MIN", "FIGURES", "Row", "printed_decimals", "agrees", "row", "shift_pure_rolling"]

#: The numbers Section III.C prints, as printed (the digits count).
PAPER = {
    "a_k0": "0.533681",
    "gamma_k0": "-1.13393",
    "h_k2.5": "0.410842",
    "h_k5": "0.515783",
    "gamma_k2.5": "-0.965672",
    "gamma_k5": "-0.797416",
    "k1": "0.233154",
    "k2": "2.64357",
    "k3": "5.20728",
    "k4": "7.80506",
    "k5": "10.9801",
    "a1": "0.300429",
    "a2": "0.491471",
    "a3": "0.538682",
    "a4": "0.609147",
    "gamma_a1": "0.931883",
    "gamma_a2": "-0.69726",
}

#: Range of the Fig. 9 sweep of k (wide enough to hold k_6, needed for the
#: self-intersection claim on [k_5, k_6]).
K_RANGE = (0.0, 14.0)
#: Smallest radius of the Fig. 10 sweep of a (units of R).
A_MIN = 0.02


def shift_pure_rolling(a):
    """Closed form (36): ``h/R = 4 (a/R) / sqrt(1 - (a/R)^2) sin(pi sqrt(1 - (a/R)^2))``.

    Shift of one symmetric figure eight of circles (35) under pure rolling
    (k = 0), from [11]; independent of the integrators.
    """
    a = np.asarray(a, float)
    c = np.sqrt(1.0 - a * a)
    return 4.0 * a / c * np.sin(np.pi * c)


def printed_decimals(text: str) -> int:
    """Number of decimals of a printed number (``"-0.69726"`` -> 5)."""
    return len(text.split(".")[1]) if "." in text else 0


def agrees(computed: float, printed: str) -> bool:
    """True when ``computed`` rounded to the printed decimals equals the printed number."""
    d = printed_decimals(printed)
    return abs(computed - float(printed)) <= 0.5 * 10.0 ** (-d) * (1 + 1e-9)

#: File names of Figs 6-12.
FIGURES = ("fig06.png", "fig07.png", "fig08.png", "fig09.png", "fig10.png", "fig11.png", "fig12.png")


@dataclass(frozen=True)
class Row:
    """One number of the paper and its reproduction.

    Attributes
    ----------
    quantity : str
        What the number is, with its unit.
    paper : float
        The value printed in the paper (for a claim: the claimed count, or 1 = true).
    computed : float
        The value computed here.
    status : str
        ``"reproduced"`` or ``"discrepancy"``.
    note : str
        How it was computed, the independent cross-checks, and for a
        discrepancy what the paper's number corresponds to instead.
    """

    quantity: str
    paper: float
    computed: float
    status: str
    note: str

    def as_dict(self) -> dict:
        return {"quantity": self.quantity, "paper": float(self.paper), "computed": float(self.computed),
                "status": self.status, "note": self.note}


def row(quantity: str, key: str, computed: float, note: str) -> Row:
    """The Row of the printed number ``PAPER[key]``: reproduced when :func:`agrees`."""
    printed = PAPER[key]
    return Row(quantity, float(printed), float(computed), "reproduced" if agrees(computed, printed) else "discrepancy",
               note)
