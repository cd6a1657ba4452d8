"""IncrementalDTW's template block: padding a template list into it, and changing the list in
place without a rebuild (the recognizer's adaptation adds, drops and replaces templates)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def pad_templates(templates: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(L_max, T, D) zero-padded stack (position-major, so a position is one contiguous row)
    and the (T,) lengths."""
    lengths = np.array([len(t) for t in templates], dtype=np.int64)
    if len(templates) == 0 or lengths.min() < 1:
        raise ValueError("need at least one template, each with at least one frame")
    dim = templates[0].shape[1]
    out = np.zeros((int(lengths.max()), len(templates), dim), dtype=np.float64)
    for k, t in enumerate(templates):
        out[: len(t), k] = t
    return out, lengths


class TemplateEdits:
    """add_templates, remove_templates, replace_template and update_templates of
    IncrementalDTW (dtw.py), on its buffers: for "native" columns of its (L, D, capacity)
    layout are moved in place; the other methods pad afresh (IncrementalDTW._set_padded)."""

    def add_templates(self, templates: Sequence[np.ndarray], at: Sequence[int] | None = None) -> None:
        """Add templates without rebuilding: each new one goes before position at[i] of the
        current order (np.insert's rule; default: at the end). With "native" a template no
        longer than the longest so far is written into a spare column (the rest shift over);
        otherwise the padded block is extended by np.insert. The kernel stays loaded, and the
        scores are those of a DTW built on the new list. The query is forgotten (as reset())."""
        new = [np.asarray(t, dtype=np.float64) for t in templates]
        if not new:
            return
        at = [self.T] * len(new) if at is None else [int(i) for i in at]
        if len(at) != len(new) or not all(0 <= i <= self.T for i in at):
            raise ValueError(f"need one position in 0..{self.T} per new template")
        if any(t.ndim != 2 or t.shape[1] != self.D or len(t) < 1 for t in new):
            raise ValueError(f"templates must be (length >= 1, {self.D}) arrays")
        lengths = np.array([len(t) for t in new], dtype=np.int64)
        # where each template of the new order comes from: >= 0 an old index, < 0 a new one
        # (np.insert's order: by position, new ones at one position in their given order)
        origin: list[int] = []
        done = 0
        for pos, i in sorted(zip(at, range(len(new)), strict=True)):
            origin += [*range(done, pos), -1 - i]
            done = pos
        origin += range(done, self.T)
        sources = list(templates)
        self.sources = [self.sources[i] if i >= 0 else sources[-1 - i] for i in origin]
        if self.method == "native" and lengths.max() <= self.L and self.T + len(new) <= len(self._len_full):
            for k, i in enumerate(origin):  # ascending: the earlier new ones are already in place
                if i < 0:
                    self._insert_column(k, new[-1 - i])
            self.reset()
            return
        L = max(self.L, int(lengths.max()))
        block = np.zeros((L, len(new), self.D))
        for k, t in enumerate(new):
            block[: len(t), k] = t
        tmpl = self.tmpl if L == self.L else np.concatenate([self.tmpl, np.zeros((L - self.L, self.T, self.D))])
        self._set_padded(np.insert(tmpl, at, block, axis=1), np.insert(self.lengths, at, lengths))
        self.reset()

    def remove_templates(self, indices: Sequence[int]) -> None:
        """Drop the templates at these positions (at least one must stay); the rest keep their
        order. The query is forgotten (as after reset())."""
        gone = {int(i) for i in indices}
        if not gone:
            return
        if min(gone) < 0 or max(gone) >= self.T or len(gone) >= self.T:
            raise ValueError(f"can drop positions 0..{self.T - 1}, and not all of them")
        drop = sorted(gone)
        self.sources = [t for i, t in enumerate(self.sources) if i not in gone]
        if self.method == "native":
            # the padding past the longest template left stays: computed, never counted
            for k in reversed(drop):
                self._delete_column(k)
        else:
            lengths = np.delete(self.lengths, drop)
            tmpl = np.delete(self.tmpl, drop, axis=1)[: int(lengths.max())]
            self._set_padded(np.ascontiguousarray(tmpl), lengths)
        self.reset()

    def replace_template(self, drop: int, template: np.ndarray, at: int) -> None:
        """Drop the template at position `drop` and put `template` at position `at` of the
        result (the count stays; the others keep their order): the adaptation's steady state,
        where an adopted motion replaces its action's oldest. With "native" and a template no
        longer than the longest so far, only the columns between the two positions move;
        otherwise as remove_templates + add_templates. The query is forgotten."""
        T = self.T
        if not (0 <= drop < T and 0 <= at < T):
            raise ValueError(f"drop and at must be positions in 0..{T - 1}")
        t = np.asarray(template, dtype=np.float64)
        if t.ndim != 2 or t.shape[1] != self.D or len(t) < 1:
            raise ValueError(f"templates must be (length >= 1, {self.D}) arrays")
        if self.method != "native" or len(t) > self.L:
            self.remove_templates([drop])
            self.add_templates([template], at=[at])
            return
        del self.sources[drop]
        self.sources.insert(at, template)
        ldt, lengths = self._ldt_full, self._len_full
        if drop < at:  # overlapping slices: numpy copies through a buffer
            ldt[:, :, drop:at] = ldt[:, :, drop + 1 : at + 1]
            lengths[drop:at] = lengths[drop + 1 : at + 1]
        elif at < drop:
            ldt[:, :, at + 1 : drop + 1] = ldt[:, :, at:drop]
            lengths[at + 1 : drop + 1] = lengths[at:drop]
        ldt[:, :, at] = 0.0
        ldt[: len(t), :, at] = t
        lengths[at] = len(t)
        self.reset()

    def update_templates(self, templates: Sequence[np.ndarray]) -> None:
        """Make `templates` the template list, where a template kept from the current list is
        the same array object and the kept ones stay in their order: the ones gone are removed
        and the new ones added in place (remove_templates, add_templates), no rebuild. Any other
        change (e.g. a reordering), and the numpy methods, pad afresh. The query is forgotten."""
        templates = list(templates)
        old = {id(t): i for i, t in enumerate(self.sources)}
        new_ids = [id(t) for t in templates]
        kept = [old[i] for i in new_ids if i in old]
        # The numpy methods size a dozen buffers by T: padding afresh measured faster for them
        # than inserting (scan: 135 against 270 us at 39 templates), so only "native" edits in place.
        if self.method != "native" or not kept or len(old) != len(self.sources) or \
                len(set(new_ids)) != len(new_ids) or kept != sorted(kept):
            self._set_padded(*pad_templates([np.asarray(t, dtype=np.float64) for t in templates]))
            self.sources = templates
            self.reset()
            return
        if len(kept) < self.T:
            kept_set = set(kept)
            self.remove_templates([i for i in range(self.T) if i not in kept_set])
        if len(templates) > len(kept):
            added, at, before = [], [], 0
            for t, i in zip(templates, new_ids, strict=True):
                if i in old:
                    before += 1
                else:
                    added.append(t)
                    at.append(before)
            self.add_templates(added, at)
        self.reset()

    def _insert_column(self, k: int, template: np.ndarray) -> None:
        """"native", room left and no longer than L: template k moves right, the new one in."""
        T, ldt, lengths = self.T, self._ldt_full, self._len_full
        ldt[:, :, k + 1 : T + 1] = ldt[:, :, k:T]  # overlapping: numpy copies through a buffer
        lengths[k + 1 : T + 1] = lengths[k:T]
        ldt[:, :, k] = 0.0
        ldt[: len(template), :, k] = template
        lengths[k] = len(template)
        self._set_count(T + 1)

    def _delete_column(self, k: int) -> None:
        T, ldt, lengths = self.T, self._ldt_full, self._len_full
        ldt[:, :, k : T - 1] = ldt[:, :, k + 1 : T]
        lengths[k : T - 1] = lengths[k + 1 : T]
        self._set_count(T - 1)
