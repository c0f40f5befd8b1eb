"""The config room's tests (nnrobust/config/)."""
