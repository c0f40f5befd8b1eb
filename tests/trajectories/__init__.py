"""The trajectories room's tests (nnrobust/trajectories/)."""
