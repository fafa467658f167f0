"""The user's own asset files (docs/language.md, "Your own URDF and MJCF assets"): URDF and MJCF arms and objects, their meshes,
scaled copies, links, inertias and the arm IK, read below every compiler stage."""
