"""The functional core, batched over envs x agents: state, ``step`` and episode end
(``core``), constraints (eq. 17-18, 20-23), communication (eq. 24, Table 2), observations,
rewards (POS) and the autopilot that flies waypoints and headings by eq. 19."""
