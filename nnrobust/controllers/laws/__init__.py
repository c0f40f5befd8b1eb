"""The registered control laws: one module each, with its compiled twin in csrc/controllers/laws/ under the
same name (nnrobust.controllers.registry imports every module here).
"""
