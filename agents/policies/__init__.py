"""Policies that fly in the environment behind one interface (:class:`base.Policy`)."""
