"""The coordinate reference system of a plan: :mod:`poc_env.crs`, re-exported here for the
mission package (plans, export, GIS import). The code lives in the base layer so that the
theory layer places velocity fields read from geographic files (:mod:`poc_env.theory.fields`)
with the same CRS as import and export."""

from __future__ import annotations

from poc_env.crs import (  # noqa: F401 -- the public API, unchanged
    CRS_KINDS,
    MAX_DISTANCE_KM,
    UTM_MAX_OFFSET_DEG,
    check_crs,
    check_origin,
    check_utm_zone,
    continuous_lon,
    crs_text,
    make_crs,
    parse_origin,
    plan_crs,
    to_geographic,
    to_local,
    utm_zone,
    utm_zones_near,
)
