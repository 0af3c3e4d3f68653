"""Execution: time laws (:mod:`.timing`), actuation by the rotors (:mod:`.actuation`), plants (:mod:`.plants`)."""
