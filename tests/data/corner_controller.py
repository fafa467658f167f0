"""A synthetic controller for `prsc falsify` tests: fails when the cube lies in one corner of its tray.

No physics: it reads the scene JSON only (the cube's offset from its tray's centre)."""

OUTCOMES = ("success", "corner")
CORNER = (0.05, 0.04)  # metres: the cube's centre beyond +x 5 cm and +y 4 cm of the tray's centre


def in_corner(scene: dict) -> bool:
    """Whether the cube c1 lies in the +x +y corner of its tray tr_1."""
    objects = {o["name"]: o for o in scene["objects"]}
    cube, tray = objects["c1"]["position"], objects["tr_1"]["position"]
    return cube[0] - tray[0] > CORNER[0] and cube[1] - tray[1] > CORNER[1]


def corner(scene, model, data):
    """The episode's outcome, from where the cube lies (the simulation is not stepped)."""
    if in_corner(scene):
        return {"outcome": "corner", "reason": "the cube lies in the tray's +x +y corner"}
    return {"outcome": "success", "reason": "the cube is not in the corner"}


corner.outcomes = OUTCOMES
