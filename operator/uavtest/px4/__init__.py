"""Facts about PX4 itself (v1.15), in one place for the runner, the spec and the built-in
simulator alike: its flight-mode tables (``modes``) and its parameters (``parameters``,
generated from PX4's own metadata and SIH logs)."""
