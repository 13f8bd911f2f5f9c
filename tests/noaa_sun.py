"""The sun's position by NOAA's general solar position formulas (Spencer's
series for the declination and the equation of time; no refraction): an
independent reference for the tests, written from the published formulas,
not from shadowgeo.sun.

    from noaa_sun import sun_vector, elevation
"""

from __future__ import annotations

import datetime as dt
import math

import numpy as np


def sun_vector(latitude: float, longitude: float, time: dt.datetime) -> np.ndarray:
    """(3,) unit vector towards the sun: x east, y north, z up."""
    utc = time.astimezone(dt.UTC)
    hour = utc.hour + utc.minute / 60.0
    gamma = 2 * math.pi / 365 * (utc.timetuple().tm_yday - 1 + (hour - 12) / 24)
    equation = 229.18 * (
        0.000075
        + 0.001868 * math.cos(gamma)
        - 0.032077 * math.sin(gamma)
        - 0.014615 * math.cos(2 * gamma)
        - 0.040849 * math.sin(2 * gamma)
    )
    declination = (
        0.006918
        - 0.399912 * math.cos(gamma)
        + 0.070257 * math.sin(gamma)
        - 0.006758 * math.cos(2 * gamma)
        + 0.000907 * math.sin(2 * gamma)
        - 0.002697 * math.cos(3 * gamma)
        + 0.00148 * math.sin(3 * gamma)
    )
    hour_angle = math.radians((hour * 60 + equation + 4 * longitude) / 4 - 180)
    phi = math.radians(latitude)
    east = -math.cos(declination) * math.sin(hour_angle)
    north = math.cos(phi) * math.sin(declination) - math.sin(phi) * math.cos(
        declination
    ) * math.cos(hour_angle)
    up = math.sin(phi) * math.sin(declination) + math.cos(phi) * math.cos(declination) * math.cos(
        hour_angle
    )
    return np.array([east, north, up])


def elevation(latitude: float, longitude: float, time: dt.datetime) -> float:
    """The sun's elevation in degrees."""
    return math.degrees(math.asin(float(sun_vector(latitude, longitude, time)[2])))
