"""From a wanted motion to buildable rig configurations: ranking the rig's four-bars, each checked."""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={"rig_design": ["rig_fourbars", "snap_function", "snap_motion", "stress_verdicts"]},
)
