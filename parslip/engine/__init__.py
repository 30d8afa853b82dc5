"""The time loop: one rank's state, the compiled kernels and the load phases (ramp, settle, drive)."""
