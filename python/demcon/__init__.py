"""demcon from Python: heat and electric conduction in sphere packings.

Scenes are demcon's RON files (docs/scenes.md), read and checked by the same code as the CLI
``demcon run``; runs release the GIL and stop on Ctrl-C; results come back as numpy arrays in SI
units. See docs/python.md.
"""

from ._demcon import RunResult, Scene, SceneError, __version__

__all__ = ["RunResult", "Scene", "SceneError", "__version__"]
