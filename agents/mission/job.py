"""One export's inputs, checked: what every format's writer receives (:class:`ExportJob`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from poc_env.agents.mission.plan import Plan


@dataclass(frozen=True)
class ExportJob:
    """A loaded plan and the export's settings, made by
    :func:`poc_env.agents.mission.export.export_plan` after every check.

    Attributes
    ----------
    plan : Plan
        The plan, checked by :func:`~poc_env.agents.mission.plan.load_plan`.
    plan_path : Path
        Where it was read (the map report finds the scenario and map file beside it).
    crs : dict
        The CRS record every coordinate is projected with.
    altitude_m, ground_m : float
        Cruise altitude and ground level in the reference ``altitude_ref``.
    altitude_ref : {"home", "amsl"}
    field_elevation_m : float
        The fields' height above mean sea level (QGC's planned home position).
    geofence : bool
        QGC: write the operating area as the inclusion fence.
    prior : None, array or path
        The prior overlay's source (None: rebuilt from the plan's scenario).
    out_dir : Path
        The folder written into.
    warning : str or None
        What the plan breaks that the QGC export refuses (a leg through a no-fly zone, a point
        outside the operating area), shown by the viewing formats (the HTML report's note).
    indices : tuple of int
        Each of ``plan["uavs"]``'s index in the plan file (the export leaves out UAVs without
        a search route); empty: the same. :meth:`where` names a UAV so.
    max_mission_items : int or None
        QGC: refuse a mission of more items (None: warn past the smallest autopilot's limit).
    """

    plan: Plan
    plan_path: Path
    crs: dict[str, Any]
    altitude_m: float
    ground_m: float
    altitude_ref: str
    field_elevation_m: float
    geofence: bool
    prior: Any
    out_dir: Path
    warning: str | None = None
    indices: tuple[int, ...] = ()
    max_mission_items: int | None = None

    def where(self, k: int) -> str:
        """``plan.uavs[i] (UAV id)`` of ``plan["uavs"][k]``, ``i`` its index in the file."""
        i = self.indices[k] if self.indices else k
        return f"plan.uavs[{i}] (UAV {self.plan['uavs'][k]['id']})"

    def path(self, suffix: str) -> Path:
        """``out_dir / (plan stem + suffix)``: every file an export writes is named so."""
        return self.out_dir / f"{self.plan_path.stem}{suffix}"
