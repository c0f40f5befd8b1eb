"""A user's code: Python classes named in an experiment, laws and twins in C++, and the
checked calls a user's part runs behind.
"""
