"""What a check writes: the report (JSON/Markdown), VTU/PVD, pictures, atomic result folders.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "document": ["finite", "write_json", "render_markdown", "MODE_TEXT"],
        "folder": ["check_writable", "check_target", "atomic_dir", "folder_lock", "MARKER"],
        "pictures": ["field_picture", "reactions_plot"],
        "vtu": ["SAFETY_CAP", "write_vtu"],
    },
)
