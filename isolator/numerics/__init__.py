"""Numerics that know nothing of tables: Runge-Kutta steppers, the DOP853 tableau, native compiling."""
