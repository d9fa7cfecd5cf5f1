@transaction_number @ext29
Feature: Transaction number
  Each TxMessage may carry any transaction number, e.g. a running number. At
  the end of a CAN cycle the number of the last TX message sent is written to
  the inputs. (000 §5.2, 003; ruling G6)

  Background:
    Given the interface is set up for 29-bit messages with 4 slots
    And transaction numbers are on

  @TN-001 @TN-002
  Scenario: The number of the last message sent
    When the PLC sends 3 messages
    And 2 cycles pass
    Then Inputs.TransactionNumber is 3

  @TN-003
  Scenario: Before any message is on the bus the number is 0
    Given the bus is blocked
    When the PLC sends 2 messages
    And 2 cycles pass
    Then Inputs.TransactionNumber is 0
    When the bus is released
    And a cycle passes
    Then Inputs.TransactionNumber is 2
