"""What `compile` finds before it samples, in one place, so that `check` finds all of it too.

A spec compiles to a sampler (syntax, IR, constraints: containers, meshes, reach), and its
object names become file names (a URDF bundle holds `<element name>.urdf`), which a file
system refuses beyond NAME_MAX bytes.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Sequence

from prsc.errors import PrscError

if TYPE_CHECKING:
    from prsc.sampling import Sampler

NAME_MAX = 255  # bytes in one file name on Linux and macOS file systems
LONGEST_SUFFIX = ".urdf"  # the longest suffix a backend puts after an object's element name


def check_file_names(program: Any) -> None:
    """Raise at the object's line when its name would make a file name longer than NAME_MAX bytes."""
    from prsc.backends.names import element_names

    objects = list(program.objects)
    for obj, element in zip(objects, element_names([o.name for o in objects])):
        size = len(os.fsencode(element + LONGEST_SUFFIX))
        if size > NAME_MAX:
            raise PrscError(f"the name of {obj.name[:40]}... makes a file name of {size} bytes "
                            f"(URDF bundle: {element[:20]}...{LONGEST_SUFFIX}); file systems allow {NAME_MAX}: "
                            "use a shorter name", obj.span)


def compile_checked(path: str, include_dirs: Sequence[str] = (), **opts: Any) -> Sampler:
    """The spec compiled as far as compile goes before sampling, with every error found there (opts: compile_sampler's)."""
    import sys
    import warnings

    from prsc.user_assets.asset_inertia import AssetFixWarning
    from prsc.sampling import compile_sampler

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AssetFixWarning)
        sampler = compile_sampler(path, include_dirs=include_dirs, **opts)
    for warning in caught:  # what prsc changed in a user's asset file, said as compile says warnings
        if issubclass(warning.category, AssetFixWarning):
            sys.stderr.write(f"prsc: warning: {warning.message}\n")
        else:
            warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
    check_file_names(sampler.program)
    return sampler
