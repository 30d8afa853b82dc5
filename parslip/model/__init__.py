"""The physical model: material constants and units (physics), lattice geometry and global ids (lattice), the time-step limit (stability)."""
