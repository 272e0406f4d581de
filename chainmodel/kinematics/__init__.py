"""Kinematics of the chain drive: the tight-span four-bar (seed 000), its closed-form
approximations, continuous sprocket rotations, and both spans' wrapping length (seed 004)."""

from .approx import (approximate, approximate_phase, approximate_release, approximate_seating,
                     exact_phase, nrmsd)
from .fourbar import Configuration, Kinematics, exact, release, seating
from .rotation import Rotation, driven_rotation
from ..geometry import centre_distance_for_links
from .wrapping import chain_geometry, roller_positions, wrap_length, wrap_length_range

__all__ = ["Configuration", "Kinematics", "exact", "release", "seating", "Rotation",
           "driven_rotation", "chain_geometry", "roller_positions", "wrap_length",
           "wrap_length_range", "centre_distance_for_links", "approximate", "nrmsd",
           "approximate_seating", "approximate_release", "approximate_phase", "exact_phase"]
