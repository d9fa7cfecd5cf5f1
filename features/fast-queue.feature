Feature: Fast CAN Queue
  No receive messages are buffered on the EL6751; the RxQueue should hold all
  messages that can arrive in one EtherCAT cycle. Received messages need not be
  acknowledged; the EL6751 counts RxCounter up when new messages arrived. In
  the transmit direction the sequence is that of the Buffered CAN Queue. Only
  11-bit identifiers, no filters, no transaction number. (000 §5.1.1, 003)

  @fast_queue @FQ-001 @FQ-002 @base11
  Scenario: The Fast CAN Queue delivers without waiting for the acknowledge
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When node 0x12 transmits 0x181 with data 01
    And a cycle passes
    And node 0x12 transmits 0x182 with data 02
    And the PLC is busy for 1 cycle
    Then Inputs.RxCounter is 2
    And Inputs.NoOfRxMessages is 1

  @fast_queue @FQ-004 @base11
  Scenario: In the Fast CAN Queue what does not fit one cycle is lost
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When other nodes transmit 7 frames
    And 3 cycles pass
    Then the PLC has received 4 messages

  @fast_queue @FQ-003 @base11
  Scenario: The Fast CAN Queue sends like the buffered queue
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    When the PLC sends 3 messages
    And 2 cycles pass
    Then Inputs.TxCounter is 1
    And the bus carries 0x100, 0x101, 0x102 in that order

  @BQ-005 @base11 @fast_queue
  Scenario: The Fast CAN Queue has no transaction number
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    And transaction numbers are on
    Then the device refuses the configuration

  @BQ-004 @base11 @fast_queue
  Scenario: The Fast CAN Queue takes no filters
    Given the interface is set up for 11-bit messages with 4 slots
    And the Fast CAN Queue
    And the filter table
      | action | kind  | first | second |
      | accept | range | 0x100 | 0x1FF  |
    Then the device refuses the configuration
