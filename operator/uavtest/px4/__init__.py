"""Facts about PX4 itself (v1.15): its parameters, generated from PX4's own metadata and logs."""
