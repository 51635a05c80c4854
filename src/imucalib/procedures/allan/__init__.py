"""The Allan procedure: noise characterisation of long static records (IEEE 952 Annex C).

Modules: :mod:`.plan` (the default plan), :mod:`.analysis` (recording → noise terms).
"""
