"""Missions in and out: geography in, flyable missions out, around one plan model.

- :mod:`~poc_env.agents.mission.plan`: the plan model (plan.json, schema 2): its typed fields,
  the checks, and the one reader and writer of the file.
- :mod:`~poc_env.agents.mission.crs`: the coordinate reference system (pyproj): ``make_crs``,
  ``to_geographic``, ``to_local``.
- :mod:`~poc_env.agents.mission.export`: ``export_plan``, the front of every format;
  :mod:`~poc_env.agents.mission.formats`: the format table and one module per format
  (GeoJSON, KML, QGroundControl, the HTML map report); :mod:`~poc_env.agents.mission.features`
  (what every format draws) and :mod:`~poc_env.agents.mission.overlay` (the prior as a PNG).
- :mod:`~poc_env.agents.mission.geoimport`: GIS layers in (GeoJSON/KML, GeoTIFF/CSV) as a
  scenario.

The planners (:mod:`poc_env.agents.planning`) build plans with the plan model and the CRS and
never import an exporter.
"""
