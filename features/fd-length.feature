Feature: CAN FD length and DLC
  CAN FD frames carry up to 64 bytes. The PLC gives the real number of bytes;
  the device rounds up to the next valid size and sets the DLC. EDL selects FD
  or classic, BRS the faster data phase, ESI the error state. (000/001 §8.3,
  corrected by ruling R1: DLC 13 is 32 bytes)

  @model @FD-LEN-002 @ERR-R1
  Scenario Outline: The DLC table
    Then DLC <dlc> means <bytes> data bytes

    Examples:
      | dlc | bytes |
      | 0   | 0     |
      | 1   | 1     |
      | 2   | 2     |
      | 3   | 3     |
      | 4   | 4     |
      | 5   | 5     |
      | 6   | 6     |
      | 7   | 7     |
      | 8   | 8     |
      | 9   | 12    |
      | 10  | 16    |
      | 11  | 20    |
      | 12  | 24    |
      | 13  | 32    |
      | 14  | 48    |
      | 15  | 64    |

  @model @FD-LEN-003 @FD-LEN-004 @ERR-R1
  Scenario Outline: Lengths round up to the next valid size
    Then a length of <length> is sent as <sent> bytes with DLC <dlc>

    Examples:
      | length | sent | dlc |
      | 8      | 8    | 8   |
      | 9      | 12   | 9   |
      | 13     | 16   | 10  |
      | 21     | 24   | 12  |
      | 25     | 32   | 13  |
      | 32     | 32   | 13  |
      | 33     | 48   | 14  |
      | 49     | 64   | 15  |

  @fd @FD-LEN-001 @FD-LEN-003 @FD-LEN-004 @FD-LEN-005 @ERR-R1
  Scenario Outline: The device sends what the PLC gives, padded with 00
    Given the interface is set up for CAN FD messages with 4 slots
    When the PLC sends an FD message 0x123 with <length> bytes with BRS
    And a cycle passes
    Then the last frame on the bus has <sent> data bytes and DLC <dlc>
    And the bytes after the first <length> are 00

    Examples:
      | length | sent | dlc |
      | 7      | 7    | 7   |
      | 10     | 12   | 9   |
      | 30     | 32   | 13  |
      | 32     | 32   | 13  |
      | 40     | 48   | 14  |
      | 64     | 64   | 15  |
