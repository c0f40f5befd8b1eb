"""What the study commands share: the sample plan, the cluster runner, tuned
settings, study folders, paired statistics and the summaries' displays.
"""
