"""The controllers room's tests (nnrobust/controllers/)."""
