"""The plant room's tests (nnrobust/plant/)."""
