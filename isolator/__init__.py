"""Pneumatic vibration-isolation tables carrying moving stages."""
