"""What a run writes or serves: run folders, figures, run deltas, the 3-D viewer, the
exported law and the virtual robot.
"""
