"""What a check writes: the report (JSON/Markdown), VTU/PVD, pictures, atomic result folders.

The public API, loaded on first use (``lazy_loader``): importing one name does not
import the whole subpackage.
"""
import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "document": ["REPORT_SCHEMA", "finite", "write_json", "md_text", "render_markdown", "MODE_TEXT", "part_label", "study_tables",
                     "allowable_label", "material_table"],
        "folder": ["MARKER", "Output", "read_report", "check_target", "check_writable", "folder_lock", "atomic_dir"],
        "check": ["document", "write_check"],
        "entries": ["part_entry", "balance"],
        "html": ["render_html", "write_html"],
        "pages": ["render_page", "markdown_html", "png_uri", "json_script"],
        "viewer": ["viewer_data"],
        "motion": ["motion_plot", "motion_gif", "structural_error_plot"],
        "picture_cache": ["cached"],
        "pictures": ["field_picture", "reactions_plot", "utilisation_plot", "part_pictures", "UTILISATION_SCALE_PCT"],
        "views": ["FieldView", "framing", "render"],
        "vtu": ["SAFETY_CAP", "write_vtu", "write_frame"],
    },
)
