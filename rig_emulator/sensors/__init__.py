"""Sensor models of the rig: five 9-axis IMU modules and four load cells (paper Sec. 4-1).

Each model draws its per-unit errors once from a seed in Python and samples raw ADC
counts in compiled per-step code (docs/explanation/conventions.md, "The compiled hot path").
"""
