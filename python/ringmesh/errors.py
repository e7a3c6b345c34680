"""The exceptions ringmesh raises: one class per module of the library's error
(``ringmesh::Error``), each with the field, node or cable at fault when the
library names one.

Bad input (a scene key, a network array, a setting) raises a subclass of
:class:`InputError`, which is also a :class:`ValueError`.
"""


class RingmeshError(Exception):
    """Every error of ringmesh.

    Attributes: ``field`` (the scene key, network attribute or setting at
    fault: ``"truss.bays"``, ``"positions"``, ``"epsilon_n"``), ``node`` and
    ``edge`` (indices), each ``None`` when the library names none.
    """

    def __init__(self, message, field=None, node=None, edge=None):
        super().__init__(message)
        self.field = field
        self.node = node
        self.edge = edge


class InputError(RingmeshError, ValueError):
    """The caller's input is at fault."""


class SceneError(InputError):
    """An invalid scene: a key out of range, unknown or missing."""


class NetworkError(InputError):
    """An invalid network: an array of the wrong shape or dtype, a NaN, an
    index out of range, an unanchored node, a force density ≤ 0."""


class SettingError(InputError):
    """A solver or run setting the solver does not have, or out of range."""


class FdmError(RingmeshError):
    """The force density method failed on a valid network."""


class UniformityError(RingmeshError):
    """A uniformity problem that cannot be stated or solved (no feasible
    design among the reasons)."""


class TrussError(RingmeshError):
    """The ring truss cannot carry or respond to its loads."""


class DesignError(RingmeshError):
    """The outer design loop cannot go on."""


class VerifyError(RingmeshError):
    """The design cannot be assembled as built."""


class StudyError(RingmeshError):
    """The accuracy study cannot run."""


class SurfaceError(RingmeshError):
    """A surface that cannot be measured, or a net target no net meets."""


class BudgetError(RingmeshError):
    """An error budget that cannot be made (its scene, design or assembly)."""


class ReportError(RingmeshError):
    """Reading or writing a file failed."""


class ShardError(RingmeshError):
    """A bad shard, or shards that cannot be merged."""


class ResourceError(RingmeshError):
    """A workload beyond the memory limit."""


class FrameError(RingmeshError):
    """An invalid frame file."""


class SizingError(RingmeshError):
    """A truss that cannot be sized."""
