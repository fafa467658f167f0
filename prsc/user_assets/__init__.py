"""The user's own asset files (LANGUAGE.md section 7): URDF and MJCF arms and objects, their meshes,
scaled copies, links, inertias and the arm IK, read below every compiler stage."""
