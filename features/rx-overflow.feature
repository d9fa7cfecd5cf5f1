@base11
Feature: Rx queue overflow and silent loss
  The EL6751 keeps 150 received messages, CCAT 512. Data not fetched in time
  are lost, and there is no indication of it. (000 §4; ruling G4: tail drop)

  Background:
    Given the interface is set up for 11-bit messages with 4 slots
    And the local Rx queue holds 6 messages

  @RXQ-003 @RXQ-004
  Scenario: A full local queue drops the newest frames and keeps the oldest
    When the PLC is busy for 1 cycle
    And node 0x01 transmits 0x101 with data 01
    And node 0x01 transmits 0x102 with data 02
    And node 0x01 transmits 0x103 with data 03
    And node 0x01 transmits 0x104 with data 04
    And node 0x01 transmits 0x105 with data 05
    And node 0x01 transmits 0x106 with data 06
    And node 0x01 transmits 0x107 with data 07
    And node 0x01 transmits 0x108 with data 08
    And node 0x01 transmits 0x109 with data 09
    And node 0x01 transmits 0x10A with data 0A
    And node 0x01 transmits 0x10B with data 0B
    And node 0x01 transmits 0x10C with data 0C
    And 4 cycles pass
    Then the PLC has received 0x101, 0x102, 0x103, 0x104, 0x105, 0x106

  @RXQ-003 @RXQ-004
  Scenario: Nothing in the image tells of the loss
    When other nodes transmit 9 frames
    And 5 cycles pass
    Then the PLC has received 6 messages
    And Inputs.RxCounter is 2
