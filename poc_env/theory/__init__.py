"""Search theory as functions of plain arrays: detection laws and POD (eq. 7-16), the optimal
search-effort bound, the time model (eq. 17-18), the prior map, search patterns (eq. 5-6) and
regions (eq. 1-4). Imports nothing of the simulator, the environments or ``agents``."""
