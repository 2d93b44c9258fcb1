"""Compensation on a simulated KR 270 campaign with known truth (``study compensation``)."""
