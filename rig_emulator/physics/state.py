"""Layout of the rig's 17-entry state vector (docs/explanation/conventions.md)."""

POS = 0  # virtual position, world ENU (Eq. 1), 3 entries
VEL = 3  # virtual velocity, world ENU, 3 entries
QUAT = 6  # unit quaternion (w, x, y, z) of R_WB (Eq. 2), 4 entries
OMEGA = 10  # body angular velocity omega_B (Eq. 3), 3 entries
MOTOR_V = 13  # motor effective voltages after the first-order lag, 4 entries
SIZE = 17
