"""The rig firmware's estimation chain (paper Sec. 4-1, Sec. 3-2): IMU and load-cell
calibration, the ensemble of the five IMU modules, the complementary attitude filter and
the guarded load-cell thrust filter.
"""
