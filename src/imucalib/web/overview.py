"""The laboratory's overview: every station's state from the shared records database.

(Pages added here by the overview's author; docs/web.md.)
"""

from __future__ import annotations

from fastapi import APIRouter

__all__ = ["router"]

router = APIRouter()
