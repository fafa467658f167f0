"""What a scene costs on each joint-law path a packed spec could take, candidate rounds or Gibbs rounds
(docs/sampling.md, "Which path"): from the fixed-seed pilots, in box draws, weighed once in sampler_plan.

A candidate draws and tests every object of the scene; a Gibbs-round proposal draws one box and
tests it against that object's partners; a scene none of whose BUDGET candidates passes is drawn
by the scalar Gibbs sweeps. The weights are measured CPU times per unit (bin_ten_parts,
bin_picking, bin_ten_parts_arm, bin_twenty_parts on one core): they are constants, not timings
of this run, so every run decides the same.
"""

from __future__ import annotations

from dataclasses import dataclass

from prsc.sampling.candidates import Pilot

CANDIDATE_BOX = 1.0  # one object of one candidate: about 0.4 us (0.32-0.44 measured)
GIBBS_PROPOSAL = 2.5  # one Gibbs-round proposal with its partner tests: about 1 us (0.95-1.45 measured)
SCALAR_SCENE = 16.0  # a scene by the scalar sweeps, in Gibbs-round scenes (measured 15 on bin_picking, 41 on bin_ten_parts_arm)
# Candidate rounds are kept while they cost at most this many times Gibbs rounds: their scenes are the joint
# law exactly, a chain's as far as its sweeps mix (bin_picking: candidate rounds measured 1.9x, estimated 2.2x, and kept).
EXACT_PREMIUM = 4.0


@dataclass(frozen=True)
class PathCosts:
    """Box draws per scene by candidate rounds and by Gibbs rounds."""

    candidates: float
    gibbs: float

    @property
    def gibbs_pays(self) -> bool:
        """Whether Gibbs rounds cost less than candidate rounds by more than their exact law is worth."""
        # pilots in which Gibbs rounds drew no proposal (a spec of one object) weigh nothing: candidate rounds stay
        return self.gibbs > 0 and self.candidates > EXACT_PREMIUM * self.gibbs

    def describe(self) -> str:
        """How the two compare (what `prsc explain` prints in the path's reason)."""
        if not self.gibbs:
            return f"a scene costs about {self.candidates:.0f} box draws by candidates; Gibbs rounds drew no proposal"
        return (f"a scene costs about {self.candidates:.0f} box draws by candidates against {self.gibbs:.0f} by Gibbs "
                f"rounds ({self.candidates / self.gibbs:.1f}x; candidate rounds, exact, are kept up to {EXACT_PREMIUM:g}x)")


def path_costs(pilot: Pilot, objects: int, gibbs_rows: int, gibbs_scenes: int) -> PathCosts:
    """The costs of a spec of `objects` objects from the candidate pilot and the proposals Gibbs rounds drew
    for `gibbs_scenes` scenes."""
    gibbs = GIBBS_PROPOSAL * gibbs_rows / gibbs_scenes
    left = (pilot.scenes - pilot.passed) / pilot.scenes  # scenes left to the scalar sweeps
    return PathCosts(CANDIDATE_BOX * objects * pilot.drawn / pilot.scenes + left * SCALAR_SCENE * gibbs, gibbs)
