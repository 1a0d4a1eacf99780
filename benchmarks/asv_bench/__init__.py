"""The airspeed velocity suite (``asv.conf.json``): what ``asv continuous BASE HEAD`` compares."""
