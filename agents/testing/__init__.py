"""Test harnesses that ship with poc-env (the top layer: they drive every input, the command
line included).

``campaign``  the hostile-input campaign (``poc-env bench campaign``; ``tests/test_campaign.py``
              runs every target in the default suite)
"""
