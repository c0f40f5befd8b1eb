"""The model room's tests (nnrobust/model/)."""
