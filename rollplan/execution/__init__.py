"""Execution: time laws (:mod:`.timing`), actuation by the rotors (:mod:`.actuation`), plants driven by
rates or torques (:mod:`.plants`), inertia estimators (:mod:`.estimate`), open- and closed-loop
execution (:mod:`.feedback`)."""
