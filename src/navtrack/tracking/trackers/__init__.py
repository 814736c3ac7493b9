"""Trackers built from the tracking primitives.

``tracker`` follows targets through a file of reports, ``multisensor`` fuses several sensors'
scans (S-D assignment JPDA), ``particle`` is the joint multitarget particle filter of the foveal
sensor, ``sensor_control`` chooses where that sensor looks, and ``autotune`` derives a tracker's
settings from the reports themselves.
"""
