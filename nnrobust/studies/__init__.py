"""Many runs: the shared base (sample plan, cluster, tuned settings, study folders, paired
statistics, displays), the sibling commands sweep, tune, falsify and learning, and the study
on top of them.
"""
