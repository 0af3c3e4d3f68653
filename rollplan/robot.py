"""Robot parameters and the inertia ratio k of eq. (14).

What a robot may be is written once, as data: :data:`ROBOT_KEYS` lists every
key of a robot (the fields of :class:`Robot`, the keys of a robot file and of
the ``robot`` object of a plan file) with its unit and allowed range, and
:data:`PHYSICAL_RULES` the conditions a real body meets. A key with
``required=False`` may be left out (its field then has a default of None).

The ranges keep every product of (11) and (14) far from overflow and
underflow (a radius of 1e-320 m would make k exactly 1; 1e308 m overflows
R^2). The physical rules:

* ``mass_shell <= mass_total``;
* ``J_r <= 2 J_p``: for a body of revolution, by the perpendicular-axis
  theorem, ``2 J_p = J_r + 2 int z^2 dm >= J_r`` (equality for a flat disc);
* ``J_r + 2 J_p <= 2 (mass_total - mass_shell) R^2``: the trace of a rotor's
  inertia about the centre is ``2 int |r|^2 dm``, and the rotor lies in the
  sphere and weighs at most what is not shell; so rotors with inertia need a
  mass (``mass_shell = mass_total`` leaves none).
"""

from __future__ import annotations

from dataclasses import dataclass, fields

from .core import model
from .errors import InputError, check_range, show
from .inputs import load_toml, show_path

__all__ = ["Key", "ROBOT_KEYS", "OPTIONAL_KEYS", "PHYSICAL_RULES", "Robot", "robot_from_mapping", "load_robot",
           "default_robot", "DEFAULT_ROBOT_FILE"]

#: The shipped default robot (package data, same values as ``Robot()``), documented in the file.
DEFAULT_ROBOT_FILE = "data/default_robot.toml"

@dataclass(frozen=True)
class Key:
    """One key of a robot: its name (a field of :class:`Robot`), unit, allowed range [low, high], and
    whether a robot file must give it."""

    name: str
    unit: str
    low: float
    high: float
    required: bool = True
    doc: str = ""


#: Every key of a robot, in file order (see the module docstring).
ROBOT_KEYS = (
    Key("radius", "m", 1e-6, 1e3, doc="sphere radius R"),
    Key("mass_total", "kg", 1e-12, 1e9, doc="total mass M (shell, rotors, motors, battery)"),
    Key("mass_shell", "kg", 1e-12, 1e9, doc="mass m_o of the spherical shell"),
    Key("rotor_inertia_axial", "kg m^2", 1e-40, 1e18, doc="J_r, one rotor about its spin axis"),
    Key("rotor_inertia_transverse", "kg m^2", 1e-40, 1e18, doc="J_p, one rotor about a transverse axis"),
    Key("max_rotor_rate", "rad/s", 1e-6, 1e9, required=False,
        doc="largest rotor rate |phi_i_dot| of either motor (absent: unlimited)"),
    Key("max_rotor_torque", "N m", 1e-12, 1e9, required=False,
        doc="largest motor torque |tau_i| of either motor (absent: unlimited)"),
)
#: Keys of a robot file that may be absent (absent means unlimited): the motors' limits.
OPTIONAL_KEYS = tuple(k.name for k in ROBOT_KEYS if not k.required)


def _shell_within_total(r):
    if r.mass_shell > r.mass_total:
        return (f"mass_shell = {r.mass_shell!r} is not allowed: it must not exceed mass_total = "
                f"{r.mass_total!r}")
    return None


def _body_of_revolution(r):
    if r.rotor_inertia_axial > 2.0 * r.rotor_inertia_transverse:
        return (f"rotor_inertia_axial = {r.rotor_inertia_axial!r} is not allowed: a rotor (a body of revolution) "
                f"has J_r <= 2 J_p = {2.0 * r.rotor_inertia_transverse!r} (perpendicular-axis theorem)")
    return None


def _rotors_have_mass(r):
    rotor_mass = r.mass_total - r.mass_shell
    trace = r.rotor_inertia_axial + 2.0 * r.rotor_inertia_transverse
    most = 2.0 * rotor_mass * r.radius**2
    if trace > most:
        if rotor_mass <= 0.0:
            return ("mass_shell = mass_total is not allowed with rotor inertias > 0: it leaves no mass for the "
                    "rotors")
        return (f"the rotor inertias are not allowed: J_r + 2 J_p = {trace!r} kg m^2 exceeds "
                f"2 (mass_total - mass_shell) radius^2 = {most!r} kg m^2, the most the mass that is not shell "
                "can have inside the sphere")
    return None


#: Conditions every real robot meets (module docstring): each returns a one-line message, or None.
PHYSICAL_RULES = (_shell_within_total, _body_of_revolution, _rotors_have_mass)


@dataclass(frozen=True)
class Robot:
    """Physical parameters of the two-rotor spherical robot (Section II).

    Attributes
    ----------
    radius : float
        Sphere radius R [m].
    mass_total : float
        Total mass M [kg].
    mass_shell : float
        Mass of the spherical shell m_o [kg].
    rotor_inertia_axial : float
        Moment of inertia J_r of one rotor about its spin axis [kg m^2].
    rotor_inertia_transverse : float
        Moment of inertia J_p of one rotor about a transverse axis [kg m^2].
    max_rotor_rate : float or None
        Largest rotor rate |phi_i_dot| either motor can run [rad/s]; None (the key
        absent from the file) means unlimited. Optional.
    max_rotor_torque : float or None
        Largest motor torque |tau_i| either motor can give [N m]; None means
        unlimited. Optional. The timing laws of :mod:`rollplan.execution.timing` keep
        the rotor rates and torques within both.
    """

    radius: float = 0.1
    mass_total: float = 1.2
    mass_shell: float = 0.4
    rotor_inertia_axial: float = 2.0e-4
    rotor_inertia_transverse: float = 1.2e-4
    max_rotor_rate: float | None = None
    max_rotor_torque: float | None = None

    def __post_init__(self) -> None:
        for key in ROBOT_KEYS:
            value = getattr(self, key.name)
            if value is None and not key.required:
                continue
            object.__setattr__(self, key.name, check_range(key.name, value, key.low, key.high))
        for rule in PHYSICAL_RULES:
            message = rule(self)
            if message:
                raise InputError(message)

    def _ratio(self):
        return model.inertia_ratio(self.radius, self.mass_total, self.mass_shell,
                                   self.rotor_inertia_axial, self.rotor_inertia_transverse)

    @property
    def k(self) -> float:
        """Inertia ratio k = Jxx/Jzz, eq. (14); always > 1."""
        return float(self._ratio()[0])

    @property
    def j_xx(self) -> float:
        """Jxx = Jzz + M R^2 about the contact point [kg m^2]."""
        return float(self._ratio()[1])

    @property
    def j_zz(self) -> float:
        """Jzz = 2/3 m_o R^2 + 2 J_p + J_r [kg m^2]."""
        return float(self._ratio()[2])

    def as_dict(self) -> dict:
        """The fields (limits only when set) and k."""
        d = {f.name: getattr(self, f.name) for f in fields(self)
             if f.name not in OPTIONAL_KEYS or getattr(self, f.name) is not None}
        d["k"] = self.k
        return d


def robot_from_mapping(data, where: str = "robot", derived=()) -> Robot:
    """A Robot from a mapping of :data:`ROBOT_KEYS` (a robot file's table, a plan file's ``robot`` object).

    Unknown keys are refused, except the names in ``derived`` (values computed
    from the others, such as ``k``, which are ignored). Every message starts
    with ``where`` (e.g. the file's name).
    """
    if not isinstance(data, dict):
        raise InputError(f"{where} must be a table of {', '.join(k.name for k in ROBOT_KEYS)}")
    allowed = [k.name for k in ROBOT_KEYS]
    unknown = sorted(str(n) for n in set(data) - set(allowed) - set(derived))
    if unknown:
        raise InputError(f"{where}: unknown key {show(unknown[0])}; allowed: {', '.join(allowed)}")
    given = {k.name: data[k.name] for k in ROBOT_KEYS
             if k.name in data and not (data[k.name] is None and not k.required)}  # None: an optional key unset
    missing = [k.name for k in ROBOT_KEYS if k.required and k.name not in given]
    if missing:
        raise InputError(f"{where}: missing key {missing[0]!r}")
    for name, value in given.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise InputError(f"{where}: {name} = {show(value)} is not allowed: it must be a number")
    try:
        return Robot(**given)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None


def load_robot(path) -> Robot:
    """Read a robot from a TOML file of the keys of :data:`ROBOT_KEYS` (see :mod:`rollplan.inputs` for what
    files are read)."""
    data = load_toml(path, "robot file")
    return robot_from_mapping(data, f"robot file {show_path(path)}")


def default_robot() -> Robot:
    """The shipped default robot, read from :data:`DEFAULT_ROBOT_FILE` (package data)."""
    from importlib.resources import as_file, files

    with as_file(files(__package__).joinpath(DEFAULT_ROBOT_FILE)) as path:
        return load_robot(path)
