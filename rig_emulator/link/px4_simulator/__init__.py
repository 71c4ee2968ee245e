"""PX4 in the loop: the rig as the simulator of PX4 SITL or a HIL board over PX4's Simulator MAVLink API
(``serve --px4-simulator``), and the PX4 SITL airframe for the rig (``10090_none_hilms``)."""
