"""Test harnesses that ship with poc-env (the top layer: they drive every input, the command
line included).

``campaign``  the hostile-input campaign (``poc-env bench campaign``; ``tests/test_campaign.py``
              runs every target in the default suite)
``flights``   one policy's episode with its eq. 20 (no-fly, out-of-bounds) steps counted, as
              the airspace tests and scripts need it
``terrain``   a valley with a 4,000 m wall (:func:`terrain.wall_scenario`) for the
              altitude-layer tests and scripts
"""
