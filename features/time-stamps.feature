@timestamp @ext29 @transaction_number
Feature: Time stamps
  CCAT-based controllers deliver each received frame with the time it arrived,
  a 64-bit integer in nanoseconds; only in 29-bit mode with transaction number.
  (000 §5.3, §2 footnote 2; ruling G8)

  @TS-001 @TS-003 @TS-004
  Scenario: Each message carries the end of its reception
    Given the interface is set up for 29-bit messages with 4 slots
    And transaction numbers are on
    And time stamps are on
    When node 0x01 transmits 0x101 with data 01
    And node 0x02 transmits 0x102 with data 02
    And a node transmits the 29-bit 0x1000 with data 03
    And 2 cycles pass
    Then each message's time stamp is the end of its reception

  @TS-002 @PROF-004
  Scenario: No time stamp without the transaction number
    Given the interface is set up for 29-bit messages with 4 slots
    And time stamps are on
    Then the device refuses the configuration
