"""Scoring policies on the same episodes (``evaluate``) and the paper's §6 (``paper``)."""
