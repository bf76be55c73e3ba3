//! Operand encoding of the iteration stream.
//!
//! Every operand is an unsigned 32-bit value stored in one 16-bit word when it is below
//! [`ESCAPE`], and otherwise as `ESCAPE, low16, high16`. Operands are back-offsets or small
//! signed offsets (see [`zigzag`]), so on meshes the compiler walks breadth-first nearly all of
//! them fit in one word; the escape keeps any mesh size representable.

/// The word announcing a 32-bit operand in the next two words.
pub const ESCAPE: u16 = 0xFFFF;

/// Appends `value` to `code`.
pub fn push(code: &mut Vec<u16>, value: u32) {
    if value < u32::from(ESCAPE) {
        code.push(value as u16);
    } else {
        code.push(ESCAPE);
        code.push(value as u16);
        code.push((value >> 16) as u16);
    }
}

/// Reads an operand at `*pc`, advancing it; `None` when the stream ends inside the operand.
pub fn read_checked(code: &[u16], pc: &mut usize) -> Option<u32> {
    let first = *code.get(*pc)?;
    if first != ESCAPE {
        *pc += 1;
        return Some(u32::from(first));
    }
    let lo = *code.get(*pc + 1)?;
    let hi = *code.get(*pc + 2)?;
    *pc += 3;
    Some(u32::from(lo) | (u32::from(hi) << 16))
}

/// Reads an operand of a verified stream at `*pc`, advancing it.
///
/// # Panics
/// Panics (index out of bounds) only if the stream was not verified.
#[inline(always)]
pub fn read(code: &[u16], pc: &mut usize) -> u32 {
    let first = code[*pc];
    if first != ESCAPE {
        *pc += 1;
        u32::from(first)
    } else {
        let v = u32::from(code[*pc + 1]) | (u32::from(code[*pc + 2]) << 16);
        *pc += 3;
        v
    }
}

/// Maps a signed offset to an unsigned one: 0, -1, 1, -2, 2, ... become 0, 1, 2, 3, 4, ...
pub fn zigzag(value: i64) -> u32 {
    ((value << 1) ^ (value >> 63)) as u32
}

/// The inverse of [`zigzag`].
#[inline(always)]
pub fn unzigzag(value: u32) -> i64 {
    i64::from(value >> 1) ^ -i64::from(value & 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn operands_round_trip_across_the_escape() {
        let values = [0, 1, 0xFFFE, 0xFFFF, 0x1_0000, 0x1234_5678, u32::MAX];
        let mut code = Vec::new();
        for v in values {
            push(&mut code, v);
        }
        assert_eq!(code.len(), 3 + 4 * 3);
        let mut pc = 0;
        let mut fast = 0;
        for v in values {
            assert_eq!(read_checked(&code, &mut pc), Some(v));
            assert_eq!(read(&code, &mut fast), v);
        }
        assert_eq!(pc, code.len());
        assert_eq!(read_checked(&code, &mut pc), None);
        let mut truncated = 0;
        assert_eq!(read_checked(&[ESCAPE, 1], &mut truncated), None);
    }

    #[test]
    fn zigzag_round_trips() {
        for v in [-70_000i64, -2, -1, 0, 1, 2, 65_000, 1 << 30] {
            assert_eq!(unzigzag(zigzag(v)), v);
        }
        assert_eq!(zigzag(-1), 1);
        assert_eq!(zigzag(1), 2);
    }
}
