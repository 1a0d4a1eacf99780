"""The table as an FMI 2.0 FMU for other simulation tools (``isolator fmu``), and the packaging every FMU the
toolkit writes shares."""

from isolator.fmu.plant import write_fmu

__all__ = ["write_fmu"]
