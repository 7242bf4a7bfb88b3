"""The manipulation domains (Shelf, OpenDrawer, OpenDoor): today the initial belief
(:mod:`strug_manip.domains.manipulation.belief`); the POMDP itself comes with the skills."""
