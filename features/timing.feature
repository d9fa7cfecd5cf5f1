@model
Feature: Frame timing and buffer size
  How big the buffer must be, or how fast the task: a CAN telegram with 11-bit
  identifier and 8 bytes takes about 260 µs at 500 kbit/s … The table of
  telegram times from CiA. (000/001 §4, rulings R3 and R4)

  @TIM-004 @TIM-005 @TIM-001 @TIM-002 @ERR-R3
  Scenario Outline: Every cell of the CiA table lies within the bit model
    Then <bytes> data bytes at <rate> kbit/s, printed as <ms> ms, lie between the nominal and the worst-case frame time

    Examples:
      | rate | bytes | ms   |
      | 50   | 0     | 1.09 |
      | 50   | 4     | 1.86 |
      | 50   | 7     | 2.34 |
      | 50   | 8     | 2.62 |
      | 125  | 0     | 0.44 |
      | 125  | 3     | 0.67 |
      | 125  | 8     | 1.05 |
      | 250  | 0     | 0.22 |
      | 250  | 5     | 0.41 |
      | 250  | 8     | 0.52 |
      | 500  | 0     | 0.11 |
      | 500  | 6     | 0.22 |
      | 500  | 8     | 0.26 |
      | 1000 | 0     | 0.05 |
      | 1000 | 8     | 0.13 |

  @TIM-006 @ERR-R3
  Scenario Outline: Only the 50 kbit/s, 7-byte cell breaks its row
    Then the cell for <bytes> bytes at <rate> kbit/s is <verdict>

    Examples:
      | rate | bytes | verdict    |
      | 50   | 7     | flagged    |
      | 50   | 6     | consistent |
      | 125  | 7     | consistent |
      | 500  | 6     | consistent |

  @TIM-007 @TIM-008 @ERR-R4
  Scenario Outline: The manual's buffer sizes
    Then at <rate> kbit/s with <bytes>-byte frames a <cycle> µs cycle needs <slots> slots

    Examples:
      | rate | bytes | cycle | slots |
      | 500  | 8     | 1000  | 4     |
      | 500  | 8     | 5000  | 20    |
      | 1000 | 0     | 1000  | 20    |

  @TIM-008 @ERR-R4
  Scenario Outline: The buffer size that cannot overflow (R4, amended)
    Then at <rate> kbit/s with <bytes>-byte frames the advisor recommends <slots> slots for a <cycle> µs cycle

    Examples:
      | rate | bytes | cycle | slots |
      | 500  | 8     | 1000  | 5     |
      | 500  | 8     | 5000  | 23    |
      | 1000 | 0     | 1000  | 22    |

  @TIM-003 @FD-BIT-004
  Scenario Outline: A CAN FD frame's two phases at their own bit rates
    Then a CAN FD frame of <bytes> bytes at <rates> kbit/s takes <switched> µs with BRS and <plain> µs without, not counting stuff bits

    Examples:
      | bytes | rates    | switched | plain  |
      | 64    | 500/2000 | 334.5    | 1158.0 |
      | 8     | 500/2000 | 108.0    | 252.0  |
      | 64    | 500/500  | 1158.0   | 1158.0 |
