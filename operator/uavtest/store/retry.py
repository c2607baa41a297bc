"""Bounded, logged retries shared by the S3 stores (tenacity).

Exponential backoff with jitter until ``retry_total`` seconds have passed; each retry is logged with
the operation, the key and the error (never a credential or a signature).
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from tenacity import (
    RetryCallState,
    Retrying,
    retry_if_exception,
    stop_after_delay,
    wait_exponential,
    wait_random,
)

from uavtest.store.settings import S3Settings

__all__ = ["retrying"]


def retrying(
    settings: S3Settings,
    operation: str,
    key: str,
    *,
    transient: Callable[[BaseException], bool],
    describe: Callable[[BaseException], str],
    log: logging.Logger,
) -> Retrying:
    """A tenacity ``Retrying`` that retries ``transient`` errors, logs each retry and re-raises the last."""

    def before_sleep(state: RetryCallState) -> None:
        error = state.outcome.exception() if state.outcome else None
        wait = state.next_action.sleep if state.next_action else 0.0
        log.warning(
            "store %s %s failed (%s); retry %d in %.1f s",
            operation,
            key,
            describe(error) if error else "?",
            state.attempt_number,
            wait,
        )

    s = settings
    backoff = wait_exponential(multiplier=s.retry_initial, max=s.retry_max) + wait_random(0, s.retry_initial)
    return Retrying(
        stop=stop_after_delay(s.retry_total),
        wait=backoff,
        retry=retry_if_exception(transient),
        before_sleep=before_sleep,
        reraise=True,
    )
