"""The floor every other stands on: exceptions, numeric limits, small linear algebra, the
kinds' registry shape, key checks, search coordinates, twins, the version, signals, forked jobs,
shipped files, table text, drawing, progress and the one folder protocol.
"""
