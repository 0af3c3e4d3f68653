"""The one colour convention of rollplan's figures: a colour means the same thing in every figure.

============================  ===========================================================
``LEAF``                      1st half-step (leaf of radius a) red, 2nd (radius b) blue,
                              as in the paper's figures
``PLANNER``                   geometric phase brown, direct collocation orange
``ROTOR``                     rotor 1 (axis n1) purple, rotor 2 (axis n2) green: rates,
                              angles, torques and the rotor axes in the animation
``AXIS_N3``                   the body axis n3 (no rotor) grey
``OMEGA``                     components x, y, z of the angular velocity: olive, cyan, pink
``PLANNED``, ``SIMULATED``    a planned motion (grey, dashed) against a simulated one (black)
``MARK``                      start and target marks, the fold of the atlas: black
``COMPUTED``, ``PRINTED``     a value computed by rollplan (black) and the value printed in
                              the paper (magenta)
``PIECE``, ``TURN``           composed plans: approach roll dark goldenrod, departure roll dark
                              slate grey, the circles of a turn in place dark khaki and violet red
``LAW``, ``LIMIT``            timing laws: min-jerk navy, nonstop-min-jerk teal, smooth-cruise
                              goldenrod, time-optimal black; the motors' limits dim grey
``FAMILY``                    leaf families: circles saddle brown, viviani medium sea green,
                              triangle steel blue, square orchid
============================  ===========================================================

Every figure that uses a colour names it in a legend (or a colour bar for maps).
"""

from __future__ import annotations

__all__ = ["LEAF", "LEAF_LABELS", "PLANNER", "PLANNER_LABELS", "ROTOR", "ROTOR_LABELS", "AXIS_N3", "OMEGA",
           "OMEGA_LABELS", "PLANNED", "SIMULATED", "MARK", "REST",
           "COMPUTED", "PRINTED", "PIECE", "PIECE_LABELS", "TURN", "TURN_LABELS", "LAW", "LIMIT", "FAMILY"]

LEAF = ("tab:red", "tab:blue")
LEAF_LABELS = ("1st half-step (leaf a)", "2nd half-step (leaf b)")
PLANNER = {"geometric": "tab:brown", "collocation": "tab:orange"}
PLANNER_LABELS = {"geometric": "geometric phase", "collocation": "collocation"}
ROTOR = ("tab:purple", "tab:green")
ROTOR_LABELS = ("rotor 1 (axis n1)", "rotor 2 (axis n2)")
AXIS_N3 = "tab:gray"
OMEGA = ("tab:olive", "tab:cyan", "tab:pink")
OMEGA_LABELS = ("$\\omega_x$", "$\\omega_y$", "$\\omega_z$")
PLANNED = "0.55"
SIMULATED = "black"
MARK = "black"
COMPUTED = "black"
PRINTED = "magenta"
#: Thin vertical lines at the rest instants between leaves of a timed motion.
REST = "0.85"
#: Pieces of a composed plan other than figure eights: the rolls along great circles to and from the pole.
PIECE = {"approach": "darkgoldenrod", "departure": "darkslategray"}
PIECE_LABELS = {"approach": "approach roll (to the pole)", "departure": "departure roll (from the pole)"}
#: The two circles of each pair of a turn in place.
TURN = ("darkkhaki", "mediumvioletred")
TURN_LABELS = ("turn in place, 1st circle", "turn in place, 2nd circle")
#: Timing laws (rollplan.execution.timing.LAWS), in the phase plane and wherever laws are compared.
LAW = {"min-jerk": "navy", "nonstop-min-jerk": "teal", "smooth-cruise": "goldenrod", "time-optimal": "black"}
#: Motor limits (dashed) and the maximum velocity curve in the timing figures.
LIMIT = "dimgray"
#: Leaf families of the figure eight (rollplan.core.families.FAMILIES).
FAMILY = {"circles": "saddlebrown", "viviani": "mediumseagreen", "triangle": "steelblue", "square": "orchid"}
