"""McKibben muscles (Tondu and Lopez), declared: their types live in ``muscle_types`` with
``kind: mckibben``; the law is :mod:`tca_casadi.model.laws.mckibben`."""
import math

from .base import Declaration, LawParameter

#: the braid angle where the muscle stops pulling, ``atan(sqrt 2)`` = 54.7 deg
NEUTRAL_ANGLE = math.atan(math.sqrt(2.0))


class McKibben(Declaration):
    """One McKibben muscle (SI). Its type lives in ``muscle_types`` with ``kind: mckibben``."""
    KIND = "mckibben"
    INPUT = ("pressure", "pressure", 0.0)
    PARAMETERS = (
        LawParameter("radius", "length", 2e-3, "initial radius of the braided sleeve r0 [m]"),
        LawParameter("braid_angle", "angle", math.radians(20.0), "initial braid angle alpha0 [rad]"),
        LawParameter("correction", "dimensionless", 1.0, "Tondu and Lopez's k (1: Chou and Hannaford)"),
        LawParameter("rest_length", "length", None, "rest length l0 [m] (default: the path's l*)"),
    )
    OPTIONS = {"max_pressure": ("pressure", 600e3)}
    RANGE_KEYS = ("max_pressure",)

    @classmethod
    def range_of(cls, config):
        return (0.0, config.max_pressure)

    @classmethod
    def validate_type(cls, config):
        if not config.braid_angle < NEUTRAL_ANGLE:
            raise ValueError(f"braid_angle {math.degrees(config.braid_angle):.4g} deg must be below "
                             "54.7 deg (the neutral angle, where the muscle stops pulling)")
        if not config.correction >= 1.0:
            raise ValueError(f"correction (Tondu-Lopez k) {config.correction:g} must be at least 1")


DECLARATION = McKibben
