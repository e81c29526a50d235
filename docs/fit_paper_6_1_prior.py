"""Fit the mixture weights of the paper_6_1 prior so its region POCs equal Table 4's.

The paper's Fig. 15 map is not published. configs/paper_6_1.yaml uses one Gaussian component per
§6.1.1 polygon (centred on the polygon's centroid) plus a uniform background; this script
solves for the component weights and the background share with non-negative least squares so
that the POC inside each polygon (area-weighted) equals Table 4's POC column. Run:

    .venv/bin/python docs/fit_paper_6_1_prior.py

and copy the printed weights into configs/paper_6_1.yaml.
"""

import numpy as np
from scipy.optimize import nnls
from shapely.geometry import Polygon

from poc_env.config import GaussianComponent, load_scenario
from poc_env.probability_map import Grid, gaussian_mixture
from poc_env.regions import cell_overlap
from poc_env.survey import load_regions

TABLE4_POC = np.array([0.1611, 0.1600, 0.1233, 0.2146, 0.1288, 0.1805])


def main() -> None:
    sc = load_scenario("paper_6_1")
    grid = Grid.from_config(sc.map)
    regions = load_regions("paper_6_1_polygons").regions
    cols = []
    for r in regions:
        poly = Polygon(r.vertices)
        c = poly.centroid
        sig = 0.3 * np.sqrt(poly.area)
        comp = GaussianComponent(mean_m=(c.x, c.y), sigma_m=(sig, sig), weight=1.0)
        cols.append(gaussian_mixture(grid, [comp], background=0.0))
    cols.append(np.full(grid.shape, 1.0 / (grid.nx * grid.ny)))
    overlaps = [cell_overlap(r, grid) for r in regions]
    a = np.array([[np.sum(o * col) for col in cols] for o in overlaps])
    a = np.vstack([a, np.ones(len(cols)) * 10.0])
    b = np.append(TABLE4_POC, 10.0)
    w, res = nnls(a, b)
    print("residual", res)
    for r, wk in zip(regions, w[:-1]):
        poly = Polygon(r.vertices)
        print(
            f"centroid_km=({poly.centroid.x / 1e3:.1f}, {poly.centroid.y / 1e3:.1f}) "
            f"sigma_km={0.3 * np.sqrt(poly.area) / 1e3:.1f} weight={wk:.6f}"
        )
    print(f"background={w[-1]:.6f}")


if __name__ == "__main__":
    main()
