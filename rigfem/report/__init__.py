"""What a check writes: the report (JSON/Markdown), VTU/PVD, pictures, atomic result folders.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "document": ["finite", "write_json", "render_markdown"],
        "folder": ["MARKER", "Output", "read_report", "check_writable", "folder_lock", "atomic_dir"],
        "check": ["document", "write_check"],
        "entries": ["part_entry", "balance"],
        "html": ["render_html", "write_html"],
        "pages": ["render_page", "markdown_html", "png_uri", "json_script"],
        "viewer": ["viewer_data"],
        "motion": ["motion_plot", "motion_gif", "structural_error_plot"],
        "picture_cache": ["cached"],
        "pictures": ["reactions_plot", "part_pictures", "UTILISATION_SCALE_PCT"],
        "views": ["render"],
        "vtu": ["write_vtu"],
    },
)
