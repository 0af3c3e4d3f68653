"""Robot parameters and the inertia ratio k of eq. (14)."""

from __future__ import annotations

from dataclasses import dataclass, fields

from .core import model
from .errors import InputError, check_range

__all__ = ["Robot", "load_robot", "default_robot", "DEFAULT_ROBOT_FILE", "OPTIONAL_KEYS"]

#: The shipped default robot (package data, same values as ``Robot()``), documented in the file.
DEFAULT_ROBOT_FILE = "data/default_robot.toml"
#: Keys of a robot file that may be absent (absent means unlimited): the motors' limits.
OPTIONAL_KEYS = ("max_rotor_rate", "max_rotor_torque")


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
        for f in fields(self):
            if f.name not in OPTIONAL_KEYS or getattr(self, f.name) is not None:
                check_range(f.name, getattr(self, f.name), 0.0, None, low_open=True)
        if self.mass_shell > self.mass_total:
            raise InputError(f"mass_shell = {self.mass_shell:g} is not allowed: it must not exceed "
                             f"mass_total = {self.mass_total:g}")

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


def load_robot(path) -> Robot:
    """Read a robot from a TOML file with the fields of :class:`Robot` (the :data:`OPTIONAL_KEYS` may be absent)."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except OSError as exc:
        raise InputError(f"robot file {str(path)!r} cannot be read: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"robot file {str(path)!r} is not valid TOML: {exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"robot file {str(path)!r} is not valid TOML: it is not UTF-8 text") from None
    names = [f.name for f in fields(Robot)]
    unknown = sorted(set(data) - set(names))
    if unknown:
        raise InputError(f"robot file {str(path)!r}: unknown key {unknown[0]!r}; allowed: {', '.join(names)}")
    missing = [n for n in names if n not in data and n not in OPTIONAL_KEYS]
    if missing:
        raise InputError(f"robot file {str(path)!r}: missing key {missing[0]!r}")
    for n in data:
        if isinstance(data[n], bool) or not isinstance(data[n], (int, float)):
            raise InputError(f"robot file {str(path)!r}: {n} = {data[n]!r} is not allowed: it must be a number")
    try:
        return Robot(**data)
    except InputError as exc:
        raise InputError(f"robot file {str(path)!r}: {exc}") from None


def default_robot() -> Robot:
    """The shipped default robot, read from :data:`DEFAULT_ROBOT_FILE` (package data)."""
    from importlib.resources import as_file, files

    with as_file(files(__package__).joinpath(DEFAULT_ROBOT_FILE)) as path:
        return load_robot(path)
