"""Motion backends behind one interface: exact event-driven kinematics, pymunk physics and the
discrete cell model."""

#: the package itself exports nothing: its modules are the interface (import them)
__all__: list[str] = []
