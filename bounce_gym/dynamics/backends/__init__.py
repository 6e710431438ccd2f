"""Motion backends behind one interface: exact event-driven kinematics, pymunk physics and the
discrete cell model."""
