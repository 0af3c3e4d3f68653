"""The commands of ``rollplan``, one module each: ``cmd_<name>(args)`` runs it, ``register(sub)`` adds its parser."""
