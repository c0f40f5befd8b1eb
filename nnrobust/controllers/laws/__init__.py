"""The registered control laws: one module each, with its compiled twin in csrc/controllers/laws/ under the
same name; importing this package imports every module here (nnrobust.core.kinds.import_modules).
"""

from ...core.kinds import import_modules as _import_modules

_import_modules(__name__, __path__)  # every module registers its law at import
