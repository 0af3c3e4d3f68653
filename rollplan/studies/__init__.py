"""Studies built on the planners: the paper's case study (:mod:`.paper`), the reachability atlas
(:mod:`.atlas`), batch planning (:mod:`.batch`) and the comparison of the two planners (:mod:`.comparison`)."""
