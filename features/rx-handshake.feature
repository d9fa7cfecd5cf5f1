@base11
Feature: Rx handshake
  RxCounter shows whether data are new in the buffer; NoOfRxMessages tells how
  many. Having fetched the data, the PLC sets Outputs.RxCounter := Inputs.RxCounter,
  so the interface knows it may fill the buffer again. (000/001 §6, 003)

  Background:
    Given the interface is set up for 11-bit messages with 4 slots

  @HS-RX-002 @HS-RX-003 @BQ-002
  Scenario: Received messages reach the PLC with RxCounter and NoOfRxMessages
    When node 0x12 transmits 0x181 with data 01 02
    And node 0x13 transmits 0x182 with data 03
    And a cycle passes
    Then Inputs.RxCounter is 1
    And Inputs.NoOfRxMessages is 2
    When a cycle passes
    Then the PLC has received 0x181, 0x182
    And the PLC has received 0x181 with data 01 02

  @HS-RX-001 @HS-RX-004
  Scenario: The device waits until the PLC has released the buffer
    When node 0x12 transmits 0x181 with data 01
    And a cycle passes
    And node 0x12 transmits 0x281 with data 02
    And the PLC is busy for 3 cycles
    Then Inputs.RxCounter is 1
    And Inputs.NoOfRxMessages is 1
    And the PLC has received 0 messages
    When 3 cycles pass
    Then Inputs.RxCounter is 2
    And the PLC has received 0x181, 0x281

  @HS-RX-006
  Scenario: No new messages, no new RxCounter
    When 5 cycles pass
    Then Inputs.RxCounter is 0
    And the PLC has received 0 messages

  @HS-RX-007
  Scenario: Messages enter in the order received, at most one buffer per cycle
    When other nodes transmit 10 frames
    And a cycle passes
    Then Inputs.NoOfRxMessages is 4
    When 6 cycles pass
    Then the PLC has received 10 messages

  @HS-RX-007 @RXQ-006
  Scenario Outline: NoOfRxMessages reaches the buffer size when more arrive than fit
    When other nodes transmit <arrived> frames
    And a cycle passes
    Then Inputs.NoOfRxMessages is <in the image>

    Examples:
      | arrived | in the image |
      | 1       | 1            |
      | 3       | 3            |
      | 4       | 4            |
      | 9       | 4            |

  @RXQ-005
  Scenario: A 29-bit frame does not reach the 11-bit interface
    When a node transmits the 29-bit 0x1234567 with data 01
    And node 0x12 transmits 0x181 with data 02
    And 2 cycles pass
    Then the PLC has received 0x181

  @HS-RX-005 @HS-TX-005
  Scenario: RxCounter wraps from 65535 to 0
    When a node transmits one frame in each of the next 65537 cycles
    Then Inputs.RxCounter is 1
