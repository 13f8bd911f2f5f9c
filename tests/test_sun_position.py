"""The sun's position against an external reference: NREL's Solar Position
Algorithm (Reda and Andreas, 2004, NREL/TP-560-34302), whose worked example is
17 October 2003, 12:30:30 at UTC-7, 39.742476 N, 105.1786 W, 1830.14 m up:
zenith 50.111622 degrees, azimuth 194.340241 degrees (clockwise from north),
refraction included (820 mbar, 11 C there; astral's standard atmosphere
differs from it by far less than the 0.01 degrees asked)."""

from __future__ import annotations

import datetime as dt
import math

import pytest

import shadowgeo as sg
from shadowgeo.sun import sun_position

SPA_WHEN = dt.datetime(2003, 10, 17, 12, 30, 30, tzinfo=dt.timezone(dt.timedelta(hours=-7)))
SPA_LATITUDE, SPA_LONGITUDE = 39.742476, -105.1786
SPA_ZENITH, SPA_AZIMUTH = 50.111622, 194.340241


def test_sun_position_matches_nrel_spa_within_a_hundredth_of_a_degree():
    azimuth, elevation = sun_position(SPA_LATITUDE, SPA_LONGITUDE, SPA_WHEN)
    assert abs((90.0 - elevation) - SPA_ZENITH) < 0.01
    assert abs(azimuth - SPA_AZIMUTH) < 0.01


def test_sun_direction_points_the_same_way_in_a_z_up_scene():
    # Z up, north +Y: the light travels away from the sun at (azimuth, zenith)
    direction = sg.sun_direction(SPA_LATITUDE, SPA_LONGITUDE, SPA_WHEN, up="Z")
    assert direction is not None
    zenith, azimuth = math.radians(SPA_ZENITH), math.radians(SPA_AZIMUTH)
    towards = [math.sin(zenith) * math.sin(azimuth), math.sin(zenith) * math.cos(azimuth),
               math.cos(zenith)]  # fmt: skip
    cosine = -sum(a * b for a, b in zip(direction, towards, strict=True))
    assert math.degrees(math.acos(min(1.0, cosine))) < 0.015
    assert cosine == pytest.approx(1.0, abs=1e-7)
