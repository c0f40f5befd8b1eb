"""The subtasks room's tests (nnrobust/subtasks/)."""
