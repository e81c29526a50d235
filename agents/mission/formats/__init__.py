"""The export formats: one module each, one line each in :data:`FORMATS`.

``poc-env export --format NAME`` offers exactly the names of :data:`FORMATS`, the hostile-input
campaign exports a mutated plan in each, and the tests check both (tests/mission/
test_formats.py). A new format is a module here with a ``write(job) -> list[Path]`` function
(:class:`~poc_env.agents.mission.job.ExportJob` in, the files written out, each named
``job.path(suffix)``) and one :class:`Format` line below.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from poc_env.agents.mission.formats import geojson, kml, qgc, report
from poc_env.agents.mission.job import ExportJob


@dataclass(frozen=True)
class Format:
    """One export format.

    Attributes
    ----------
    name : str
        The ``--format`` value.
    write : callable
        ``write(job) -> list[Path]``: writes the files (atomically) and returns their paths.
    suffixes : tuple of str
        What follows the plan's stem in each file name it writes (``{id}``: a UAV id; a file
        that is not always written is listed too).
    extras : tuple of str
        The optional dependency groups (``pip install poc-env[...]``) it needs.
    summary : str
        One line for ``--help``.
    """

    name: str
    write: Callable[[ExportJob], list[Path]]
    suffixes: tuple[str, ...]
    extras: tuple[str, ...]
    summary: str


#: name -> format, in the order ``--help`` lists them.
FORMATS: dict[str, Format] = {
    f.name: f
    for f in (
        Format("geojson", geojson.write, (".geojson",), (), "a GeoJSON FeatureCollection"),
        Format("kml", kml.write, (".kml", "_prior.png"), (), "KML with the prior as overlay"),
        Format("qgc", qgc.write, ("_uav{id}.plan",), (), "QGroundControl missions, one per UAV"),
        Format("html", report.write, (".html",), (), "one self-contained map page"),
    )
}
