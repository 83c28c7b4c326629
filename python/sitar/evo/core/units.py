"""evo.core.units: the units of metric values and RPE deltas."""

from enum import Enum, unique


@unique
class Unit(Enum):
    """A unit, its value as evo prints it."""

    none = "unit-less"
    millimeters = "mm"
    centimeters = "cm"
    meters = "m"
    kilometers = "km"
    seconds = "s"
    degrees = "deg"
    radians = "rad"
    frames = "frames"
    percent = "%"  # a unit for display


LENGTH_UNITS = (Unit.millimeters, Unit.centimeters, Unit.meters, Unit.kilometers)
ANGLE_UNITS = (Unit.degrees, Unit.radians)
# A value in the unit times this is metres.
METER_SCALE_FACTORS = {
    Unit.millimeters: 1e-3,
    Unit.centimeters: 1e-2,
    Unit.meters: 1,
    Unit.kilometers: 1e3,
}
