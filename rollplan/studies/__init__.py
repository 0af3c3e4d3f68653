"""Studies built on the planners: the paper's case study (:mod:`.paper`), the reachability atlas
(:mod:`.atlas`), batch planning (:mod:`.batch`), the comparison of the two planners (:mod:`.comparison`)
and closed-loop execution under model error (:mod:`.closed_loop`)."""
