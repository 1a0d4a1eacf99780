"""The ``isolator`` command line: a dispatcher (:mod:`isolator.cli.app`) and the plant's subcommands."""
